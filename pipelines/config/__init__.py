"""Package data: TOML settings of the pipelines (rules.toml)."""
