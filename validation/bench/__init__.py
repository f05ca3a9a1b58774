"""Benchmarks: timings that tests must not assert on (run as ``python3 -m validation.bench.<name>``)."""
