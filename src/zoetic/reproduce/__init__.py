"""``zoetic reproduce``: the papers' checkable claims, where we stand, and how to regenerate them.

:mod:`~zoetic.reproduce.registry` reads the claims registry (claims.toml, data);
:mod:`~zoetic.reproduce.provenance` records which data files a run loaded and their hashes;
:mod:`~zoetic.reproduce.regenerate` runs a claim's experiment and writes its run record;
:mod:`~zoetic.reproduce.docs` writes docs/reproduction.md from the registry and the records.
"""

from zoetic.reproduce.provenance import figures_dir

__all__ = ["figures_dir"]
