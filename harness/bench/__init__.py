"""Layer 6, on top: the bench pipeline — validate, sweep, study, then render — for each model."""
