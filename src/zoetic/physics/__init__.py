"""How an animal MOVES: media, the compiled model every backend steps by (``model``), the
batched Numba kernel, and the one force law its NumPy reference and JAX mirror share (``law``)."""

from zoetic.physics.media import MEDIA, Medium, get_medium
from zoetic.physics.simulate import State, Trajectory, rest_state, simulate

__all__ = ["MEDIA", "Medium", "State", "Trajectory", "get_medium", "rest_state", "simulate"]
