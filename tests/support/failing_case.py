"""A validation case that fails: the harness must record it and run the others."""

NAME = "failing_case"
DESCRIPTION = "raises inside run()"


def run(quick):
    raise RuntimeError("deliberate failure")
