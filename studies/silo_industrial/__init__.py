"""Multi-level coarse graining at industrial scale: a silo of about 10^7 resolved spheres."""
