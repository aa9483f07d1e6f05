"""The EMRD benchmark suite, shipped in the package.

A model team runs it from its own repository, which holds only its registry
(``models.yaml``), its gates (``thresholds.yaml``) and its cassettes::

    pytest --pyargs pytest_emrd.benchmarks --emrd-models=models.yaml --emrd-model=NAME -n 2

``<rootdir>`` (the directory pytest is started in, when it has no pytest ini file) is where
``thresholds.yaml``, ``cassettes/`` and ``.emrd/runs/`` are looked for, as for a suite
checked into the repository. pytest-emrd's own checkout reaches the same tests through
``benchmarks/test_emrd.py``.
"""

#: The suite is collected by pytest, not imported: nothing to export.
__all__: list[str] = []
