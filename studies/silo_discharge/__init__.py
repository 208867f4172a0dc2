"""Silo discharge against the Beverloo law, resolved (validation/CASES.md D1)."""
