"""Preprocessing: mesh -> FE model -> mode shapes -> body files."""
