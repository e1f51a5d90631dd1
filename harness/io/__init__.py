"""Layer 2: files in and out — the paper and dynamic state readers, H5MD, export, run
logs, results tables. Imports core only, never the runner."""
