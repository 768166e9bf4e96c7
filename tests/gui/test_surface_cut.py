"""A hilltop cut above the ball's reach is drawn closed: a flat lid at the cut, so that the
background never shows through the hill; a wall reaching the grid's edge stays open (the view
looks over it)."""

import numpy as np

from .guitools import set_field


def open_edges(mesh) -> np.ndarray:
    """The mesh's edges that only one triangle has (n, 2, 3): where it ends."""
    faces = mesh.faces()
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    unique, count = np.unique(edges, axis=0, return_counts=True)
    return mesh.vertexes()[unique[count == 1]]


def test_a_cut_hilltop_is_closed(qtbot, window):
    set_field(qtbot, window, "landscape", "exp(-0.2*(x^2+y^2))*sin(x)")
    view = window.view
    mesh = view.surface.opts["meshdata"]
    vertexes = mesh.vertexes()
    axis = view._axis
    xs, ys = np.meshgrid(axis, axis, indexing="ij")
    z = np.exp(-0.2 * (xs ** 2 + ys ** 2)) * np.sin(xs)
    assert (z > view.cap).sum() >= 9   # the hill's top is cut away
    ends = open_edges(mesh)           # the surface ends only at the grid's edge: no hole
    rim = np.isclose(np.abs(ends[..., :2]), axis[-1]).any(axis=-1)
    assert rim.all(), ends[~rim.all(axis=1)][:3]
    top = vertexes[mesh.faces()].max(axis=1)[:, 2]
    assert np.isclose(top.max(), view.cap)   # the lid is level at the cut
    # the hill's top is there to look at (and to hide what is behind it): at the cap
    i, j = np.unravel_index(np.argmax(z), z.shape)
    assert np.isclose(view.height_at(np.array([axis[i]]), np.array([axis[j]]))[0], view.cap)


def test_walls_reaching_the_edge_stay_open():
    from rollball_app.view3d import lidded

    axis = np.linspace(-1.0, 1.0, 5)
    xs, ys = np.meshgrid(axis, axis, indexing="ij")
    bowl = xs ** 2 + ys ** 2                     # cut at 0.5: its walls reach the edge
    assert not lidded(bowl, 0.5).any()
    hill = 1.0 - bowl                            # cut at 0.5: an island of the top
    assert (lidded(hill, 0.5) == (hill > 0.5)).all() and (hill > 0.5).sum() == 5
