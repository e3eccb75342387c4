"""Listening jobs: training the classifiers and evaluating renders and recordings."""
