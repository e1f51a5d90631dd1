"""Layer 3: checking states — invariants, diff (paper and dynamic), stepdiff."""
