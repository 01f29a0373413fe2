"""Benchmark drivers behind ``zoetic bench ...``: each returns a dict of figures measured side
by side (ratios); the CLI prints them. The top layer, beside cli: nothing below imports it.

simulate: the Numba kernel's throughput and the closed-loop overhead; jax_sim: the JAX
backend's; learn: optimizers to a common E; skills: learned against hand-made skills; vision:
animat vision frames/s; aquarium: the tank in real-time factors; gym: the native vector env
against SyncVectorEnv.
"""
