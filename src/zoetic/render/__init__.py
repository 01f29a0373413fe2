"""What a scene looks like: a z-buffered rasteriser of the world's triangles, batched over
cameras (``raster``), and the triangles of a world's animals and objects (``scene``)."""

from zoetic.render.raster import Cameras, look_rotation, project, render
from zoetic.render.scene import Mesh, world_mesh

__all__ = ["Cameras", "Mesh", "look_rotation", "project", "render", "world_mesh"]
