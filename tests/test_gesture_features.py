"""PCA and Gaussian round trips of the group models."""

import numpy as np
from sklearn.covariance import ledoit_wolf

from gesture_db.features import fit_group_model, regularised_gaussian


def test_pca_round_trip_on_low_rank_data():
    rng = np.random.default_rng(0)
    basis = rng.normal(size=(4, 30))
    p = rng.normal(size=(500, 4)) @ basis + rng.normal(size=30)
    model = fit_group_model(p, n_components=4)
    assert model.explained_variance_ratio.sum() > 0.999
    np.testing.assert_allclose(model.inverse_transform(model.transform(p)), p, atol=1e-8)
    again = fit_group_model(p, n_components=4)
    np.testing.assert_array_equal(model.components, again.components)  # deterministic


def test_gaussian_round_trip_and_shrinkage():
    rng = np.random.default_rng(1)
    cov = np.array([[2.0, 0.6, 0.0], [0.6, 1.0, 0.3], [0.0, 0.3, 0.5]])
    f = rng.multivariate_normal([1.0, -2.0, 0.5], cov, size=20000)
    mean, est, alpha = regularised_gaussian(f)
    np.testing.assert_allclose(mean, [1.0, -2.0, 0.5], atol=0.05)
    np.testing.assert_allclose(est, cov, atol=0.06)
    small = f[:12]
    _m, c, a = regularised_gaussian(small)
    c2, a2 = ledoit_wolf(small)
    assert abs(a - max(a2, 1e-3)) < 1e-9
    np.testing.assert_allclose(c, c2, atol=1e-9)
    assert np.all(np.linalg.eigvalsh(c) > 0)


def test_few_notes_still_invertible():
    rng = np.random.default_rng(2)
    model = fit_group_model(rng.normal(size=(3, 27)))
    assert model.feature_dim <= 2
    d = model.mahalanobis(model.transform(rng.normal(size=(5, 27))))
    assert np.all(np.isfinite(d))


def test_block_floor_keeps_a_near_constant_entry_out_of_the_features():
    """Without the floor, an entry that barely varies (the speed at a bow change) is blown
    up to unit variance and becomes a feature of its own; with it, the features follow the
    entries that carry the note's level."""
    rng = np.random.default_rng(3)
    level = rng.normal(size=(400, 1))
    loud = level * [1.0, 0.9, 1.1] + 0.05 * rng.normal(size=(400, 3))  # a block's values
    edge = 0.01 * rng.normal(size=(400, 1))  # same unit, ~1 % of the level's spread
    p = np.hstack([loud, edge])
    blocks = np.array([0, 0, 0, 0])
    plain = fit_group_model(p, n_components=2)
    floored = fit_group_model(p, n_components=2, blocks=blocks, floor_share=0.25)
    # the second feature: the edge entry alone without the floor, the level's residue with
    assert abs(plain.components[1, 3]) > 0.9
    assert abs(floored.components[1, 3]) < 0.5
    assert floored.param_scale[3] == 0.25 * p[:, :3].std(axis=0).max()
    np.testing.assert_allclose(floored.param_scale[:3], p[:, :3].std(axis=0))
