"""Silo discharge of coarse-grained parcels against the resolved study (validation/CASES.md D1)."""
