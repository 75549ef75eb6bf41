"""The simulated home: generator, scenarios, PyBullet scene and the world server."""
