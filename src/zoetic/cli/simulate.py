"""``zoetic simulate`` and ``zoetic animals``."""
