"""What the command line's help says of a sweep: the scene keys it varies and how long it waits
for a cluster. Plain values, in a module that imports nothing, so ``rollball sweep --help``
answers without loading the simulation."""

# The scene keys a sweep may vary (dotted, as in scene files), with their units.
KEYS: dict[str, str] = {
    "start.x": "m",
    "start.y": "m",
    "start.vx": "m/s",
    "start.vy": "m/s",
    "start.spin": "rad/s",
    "ball.radius": "m",
    "ball.mass": "kg",
    "gravity": "m/s²",
    "integrator.dt": "s",
    "duration": "s",
    "contact.friction": "",      # μ (a scene whose friction is null sweeps from ∞: always enough)
    "contact.restitution": "",   # e
    "contact.rolling_resistance": "",   # c_rr (version 4)
    "contact.spin_friction": "",        # μ_s
    "air.density": "kg/m³",             # ρ (with air.drag_coefficient: both 0 or both > 0)
    "air.drag_coefficient": "",         # C_d
    "stop_at_rest": "",                 # 0 or 1: whether a run ends where the ball comes to rest
}

# Keys that are true or false in a scene: swept as 0 (false) and 1 (true).
SWITCHES = ("stop_at_rest",)

CONNECT_TIMEOUT = 10.0   # seconds to reach a Dask scheduler and hear it answer
WORKER_TIMEOUT = 60.0    # seconds to wait for a first worker (and for one to come back)
