"""``zoetic san ...``: sensor-actuator networks for planar creatures."""
