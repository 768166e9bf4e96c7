import atexit
import os
import shutil
import tempfile
from pathlib import Path

import pytest

from rollball.scene import Ball, Contact, Integrator, Scene, Start

# compiled landscapes go to a cache of the test run's own, not the user's, removed at the end (the
# cache module reads the variable when it first needs the folder, not on import)
os.environ["ROLLBALL_CACHE_DIR"] = tempfile.mkdtemp(prefix="rollball-test-cache-")
atexit.register(shutil.rmtree, os.environ["ROLLBALL_CACHE_DIR"], True)

# The examples that became version-3 scenes that fly (liftoff, cylinder, bump), as they were shipped
# in version 2: the 2011 model's scenes for the tests of the rolling ball
V2_EXAMPLES = Path(__file__).parent / "data" / "examples_v2"

# The 2011 model: always enough friction to roll, glued to the surface after a lift-off (what the
# tests of the rolling ball test; a scene made in Python flies by default, as a version-3 file)
GLUED = Contact(friction=None, restitution=0.0, after_liftoff="glued")


def make_scene(landscape, *, radius=0.1, mass=1.0, gravity=9.81, x=0.0, y=0.0, vx=0.0, vy=0.0,
               spin=0.0, method="rk4", munthe_kaas=True, dt=1e-3, duration=1.0, contact=GLUED):
    return Scene(landscape=landscape, gravity=gravity, ball=Ball(radius, mass),
                 start=Start(x, y, vx, vy, spin), integrator=Integrator(method, munthe_kaas, dt),
                 duration=duration, contact=contact)


@pytest.fixture
def scene_factory():
    return make_scene
