"""Layer 4: measuring — sweep, headline, accuracy, stability, feature cost, peer, analytic,
calibrate. Each writes CSV/JSON only; rendering is render/'s work."""
