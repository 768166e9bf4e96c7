"""What the command line's help says of a measured track and a fit: units, points, losses and the
keys a fit leaves alone. Plain values, in a module that imports nothing, so ``rollball fit --help``
answers without loading the simulation (docs/design.md §10)."""

LENGTH_UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001}   # a track's length units, in metres
TIME_UNITS = {"s": 1.0, "ms": 0.001}                   # its time units, in seconds
POINTS = ("center", "contact")                         # the point of the ball a track follows
LOSSES = ("linear", "soft_l1", "huber", "cauchy", "arctan")   # scipy's least_squares losses
# sweep keys a fit does not vary, and why
NOT_FITTED = {"integrator.dt": "the step is the method's, not the ball's",
              "duration": "the track's last time sets how long each run is",
              "stop_at_rest": "it is true or false, not a number to fit"}
