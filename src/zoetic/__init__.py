"""zoetic: physics-based artificial animals that learn to move by themselves."""

__version__ = "0.1.0"
