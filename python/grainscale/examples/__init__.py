"""Runnable example cases. Each module runs with ``python -m grainscale.examples.<name>``.

* :mod:`grainscale.examples.pour_and_settle`: glass beads poured into a closed box settle into a
  bed (the ``make demo`` / ``grainscale demo`` case).
"""
