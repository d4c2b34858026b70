"""Benchmarks: ``python -m benchmarks --out benchmarks/results.md`` (``make bench``)."""
