"""Layer 5: plots and report pages drawn from results already on disk. Nothing here runs a
binary or imports the runner (tests/unit/test_layers.py)."""
