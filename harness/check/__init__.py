"""Layer 3: checking — states (invariants, diff of the paper and dynamic models, stepdiff) and
timings (compare: two runs' figures against their noise)."""
