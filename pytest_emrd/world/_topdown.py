"""A top-down plan of a layout as PNG bytes: rooms, walls, doorways, objects, the agent.

For people checking the world (``emrd render``), not for the agent. Objects are drawn as
their footprints coloured by category (landmark green, salient blue, clutter orange) and
labelled with their ids; the agent is an arrow with its field of view out to ``visibility``.
"""

from __future__ import annotations

import io
import math

from pytest_emrd.world._geometry import footprint, walls_of
from pytest_emrd.world._model import Layout, WorldPose

CATEGORY_COLORS = {"landmark": "#2e9e4f", "salient": "#3b6fb6", "clutter": "#e08a2c"}
ROOM_FILL = {
    "Office": "#f3efe4",
    "Conference Room": "#e6edf5",
    "Kitchen": "#f4f3e6",
    "Entrance": "#f2e9df",
}


def plan_png(layout: Layout, pose: WorldPose, *, visibility: float) -> bytes:
    """The plan of ``layout`` with the agent at ``pose`` as PNG bytes.

    :param layout: The office.
    :param pose: The agent's pose, drawn with its view.
    :param visibility: How far the agent sees, metres.
    :returns: The PNG file's bytes.
    """
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import patches
    from matplotlib import pyplot as plt

    fig, ax = plt.subplots(figsize=(layout.width * 0.75 + 1, layout.depth * 0.75 + 1))
    centred = {"ha": "center", "va": "center"}
    label = {"fontsize": 13, "weight": "bold", "color": "#444444", "alpha": 0.6, "zorder": 5}
    for r in layout.rooms:
        fill = ROOM_FILL.get(r.name, "#eeeeee")
        ax.add_patch(
            patches.Rectangle((r.x0, r.z0), r.x1 - r.x0, r.z1 - r.z0, color=fill, zorder=0)
        )
        ax.text(*r.centre, r.name, **centred, **label)
    walls = walls_of(layout)
    wall = {"color": "black", "lw": 3, "solid_capstyle": "butt", "zorder": 3}
    for z, x0, x1 in walls.along_x:
        ax.plot([x0, x1], [z, z], **wall)
    for x, z0, z1 in walls.along_z:
        ax.plot([x, x], [z0, z1], **wall)
    for o in layout.objects:
        x0, z0, x1, z1 = footprint(o)
        fill = CATEGORY_COLORS.get(o.category, "grey")
        layer = {"alpha": 0.55, "zorder": 4} if o.elevation else {"alpha": 0.85, "zorder": 2}
        box = patches.Rectangle(
            (x0, z0), x1 - x0, z1 - z0, facecolor=fill, edgecolor="black", lw=0.6, **layer
        )
        ax.add_patch(box)
        ax.text(o.x, o.z, o.object_id, **centred, fontsize=5.5, zorder=6)
    # matplotlib angles are counter-clockwise from +x; headings clockwise from +z
    theta = 90.0 - pose.heading
    view = {"color": "#ffd84d", "alpha": 0.25, "zorder": 1}
    ax.add_patch(patches.Wedge((pose.x, pose.z), visibility, theta - 45, theta + 45, **view))
    dx, dz = math.cos(math.radians(theta)) * 0.6, math.sin(math.radians(theta)) * 0.6
    ax.add_patch(patches.Circle((pose.x, pose.z), 0.25, color="#d62728", zorder=7))
    ax.arrow(pose.x, pose.z, dx, dz, width=0.06, color="#d62728", zorder=7)
    ax.set(
        xlim=(-0.3, layout.width + 0.3),
        ylim=(-0.3, layout.depth + 0.3),
        aspect="equal",
        xlabel="x (m, east)",
        ylabel="z (m, north)",
        title=f"EMRD office, seed {layout.seed}",
    )
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)
    return buf.getvalue()
