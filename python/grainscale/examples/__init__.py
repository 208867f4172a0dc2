"""Short runnable examples that teach the API.

Each runs with ``python -m grainscale.examples.<name>``:

* :mod:`grainscale.examples.hopper_demo`: a conical hopper read from an STL file, filled by a
  poured stream and emptied (the ``make demo`` / ``grainscale demo`` case).
* :mod:`grainscale.examples.pour_and_settle`: glass beads poured into a closed box settle into a
  bed.

The research studies (silo discharge, coarse graining, multi-level) are in ``studies/`` at the
repository root, outside the wheel.
"""
