"""Multi-level coarse graining in a silo: a fine region at the orifice of a coarse bed."""
