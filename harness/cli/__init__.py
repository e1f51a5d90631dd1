"""Layer 6, on top: the command line (`python -m harness …`)."""
