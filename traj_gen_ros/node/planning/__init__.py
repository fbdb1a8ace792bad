"""One planning pipeline for every request: check, unwrap, plan, check."""
