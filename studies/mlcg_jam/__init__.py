"""Multi-level coarse graining where the coarse level jams: mass conserved level by level."""
