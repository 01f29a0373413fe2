"""Media as numbers: gravity, water and its surface, the floor and its directional friction."""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace

import numpy as np

from zoetic.errors import SimulationError

FAR = 1.0e9  # a water level this high means "everything is under water"; this low, "no water"
# the layout of ``Medium.as_array``: gravity, water level, buoyancy, drag, floor (1 or 0),
# floor stiffness and damping, friction forward, backward and lateral
G, LEVEL, BUOY, DRAG, FLOOR, FLOOR_K, FLOOR_C, MU_F, MU_B, MU_L = range(10)


@dataclass(frozen=True)
class Medium:
    """Where an animal lives; every field is a force-law constant in SI units."""

    name: str
    gravity: float = 9.81  # m/s^2, along -y
    water_level: float = -FAR  # m; nodes below it are submerged
    buoyancy: float = 1.0  # buoyant force / weight when submerged (1 = neutral)
    water_drag: float = 0.0  # kg/m^3: face force = -drag * A * |v| * (n.v) * n
    floor: bool = False  # a horizontal floor at y = 0
    floor_stiffness: float = 0.0  # N/m per node (penalty contact)
    floor_damping: float = 0.0  # N s/m per node
    friction_forward: float = 0.0  # Coulomb coefficient sliding along the local body axis
    friction_backward: float = 0.0  # ... sliding backward
    friction_lateral: float = 0.0  # ... sliding sideways

    def as_array(self) -> np.ndarray:
        """Return the medium as the flat float array the object kernels read (layout: G,
        LEVEL, ... above)."""
        return np.array(
            [
                self.gravity,
                self.water_level,
                self.buoyancy,
                self.water_drag,
                1.0 if self.floor else 0.0,
                self.floor_stiffness,
                self.floor_damping,
                self.friction_forward,
                self.friction_backward,
                self.friction_lateral,
            ],
            dtype=np.float64,
        )

    def with_(self, **changes) -> Medium:
        """Return a copy with some constants changed (e.g. no friction, for a control run)."""
        return replace(self, **changes)

    def describe(self) -> dict:
        """Return the medium's constants as a plain dict (for config files)."""
        return asdict(self)


MEDIA: dict[str, Medium] = {
    "ground": Medium(
        "ground",
        floor=True,
        floor_stiffness=400.0,
        floor_damping=2.0,
        friction_forward=0.1,
        friction_backward=1.0,
        friction_lateral=0.8,
    ),
    "water": Medium("water", gravity=9.81, water_level=FAR, buoyancy=1.0, water_drag=500.0),
    "sea": Medium("sea", gravity=9.81, water_level=0.0, buoyancy=1.05, water_drag=500.0),
    "vacuum": Medium("vacuum", gravity=0.0),
}


def get_medium(medium: str | Medium) -> Medium:
    """Return the built-in Medium of that name (or the Medium itself)."""
    if isinstance(medium, Medium):
        return medium
    try:
        return MEDIA[medium]
    except KeyError:
        raise SimulationError(
            f"unknown medium {medium!r} (choose from {', '.join(MEDIA)})"
        ) from None
