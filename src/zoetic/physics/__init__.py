"""How an animal MOVES: media, the batched Numba kernel, its NumPy reference."""

from zoetic.physics.media import MEDIA, Medium, get_medium
from zoetic.physics.simulate import State, Trajectory, rest_state, simulate

__all__ = ["MEDIA", "Medium", "State", "Trajectory", "get_medium", "rest_state", "simulate"]
