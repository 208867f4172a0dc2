"""Multi-level coarse graining of a bin filled by a stream: the books of the material."""
