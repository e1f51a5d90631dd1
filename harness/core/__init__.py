"""Layer 1, under everything: paths, environment, variants, scenes, tolerances, ULP
arithmetic, progress, and the runner (the one place that starts a binary)."""
