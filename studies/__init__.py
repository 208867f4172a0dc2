"""Research studies: validation and method studies built on grainscale, one folder per study with
its modules, its results and its notes. Not part of the wheel; run them from the repository root,
e.g. ``.venv/bin/python -m studies.biaxial.biaxial --output out/biaxial``. Their reduced checks are
in tests/studies."""
