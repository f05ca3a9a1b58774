"""Benchmarks: timings that tests must not assert on.

All of them in one process: ``python3 -m validation.bench [--out DIR] [--quick] [--only
NAME[,NAME]]`` or ``ffrmbs bench`` (:mod:`validation.bench.runner`); one of them alone:
``python3 -m validation.bench.<name>``.
"""
