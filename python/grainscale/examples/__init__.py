"""Short runnable examples that teach the API.

Each runs with ``python -m grainscale.examples.<name>``:

* :mod:`grainscale.examples.silo_demo`: the ``make demo`` / ``grainscale demo`` case, a silo
  whose orifice jams coarse graining, run as pure coarse graining and as a multi-level
  hierarchy against a resolved reference (shipped in ``data/silo_reference.json``, made by
  :mod:`grainscale.examples.silo_reference`); its report in ``silo_demo_report``.
* :mod:`grainscale.examples.hopper_demo`: a conical hopper read from an STL file, filled by a
  poured stream and emptied (``grainscale hopper``).
* :mod:`grainscale.examples.pour_and_settle`: glass beads poured into a closed box settle into a
  bed.

The research studies (silo discharge, coarse graining, multi-level) are in ``studies/`` at the
repository root, outside the wheel.
"""
