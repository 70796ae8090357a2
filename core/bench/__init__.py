"""Benchmarks: reproductions of published experiments (``python -m core bench ...``)."""
