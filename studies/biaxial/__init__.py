"""Coarse-grain precision vs scale factor: 2-D biaxial tests (validation/CASES.md E2)."""
