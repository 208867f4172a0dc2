"""Coarse graining the EEPA cohesive contact: confined compression in a die
(validation/CASES.md E3)."""
