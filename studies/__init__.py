"""Studies and proofs outside the installed package: the seeds' headline results
reproduced, hidden-effect trials of the workbench, thermal-model studies.

Used by ``bench/``, ``docs/`` and the tests; no node or user command needs them.
Run from the repository root (``python -m bench.<name>``).
"""
