"""Frames of the Gymnasium environments (``albot2d.envs``): ``EnvRenderer``.

Draws the world's walls and clutter, the floor seen so far (Explore), the goal (GoTo), the
robot's true pose and its latest scan. ``rgb_array`` frames come from an off-screen Agg
canvas (an ``(H, W, 3)`` uint8 array); ``human`` shows the same figure in a window.
matplotlib is imported when the first frame is drawn.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from albot2d.geometry import Pose

__all__ = ["EnvRenderer"]


class EnvRenderer:
    """One figure, redrawn per frame."""

    def __init__(self, *, human: bool = False, size_px: tuple[int, int] = (640, 480)) -> None:
        self.human = human
        self.size_px = size_px
        self._fig: Any = None

    def _figure(self) -> Any:
        if self._fig is None:
            if self.human:
                import matplotlib.pyplot as plt

                plt.ion()
                self._fig = plt.figure(figsize=(self.size_px[0] / 100, self.size_px[1] / 100))
            else:
                from matplotlib.backends.backend_agg import FigureCanvasAgg
                from matplotlib.figure import Figure

                self._fig = Figure(figsize=(self.size_px[0] / 100, self.size_px[1] / 100), dpi=100)
                FigureCanvasAgg(self._fig)
        return self._fig

    def draw(
        self,
        world: Any,
        observation: Any,
        *,
        seen: NDArray[np.bool_] | None = None,
        grid: Any = None,
        goal: Pose | None = None,
    ) -> NDArray[np.uint8]:
        from matplotlib.collections import LineCollection

        fig = self._figure()
        fig.clear()
        ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
        ax.set_axis_off()
        x0, y0, x1, y1 = world.free_space.bounds
        if seen is not None and grid is not None:
            extent = (
                grid.origin_x_m, grid.origin_x_m + grid.nx * grid.resolution_m,
                grid.origin_y_m, grid.origin_y_m + grid.ny * grid.resolution_m,
            )  # fmt: skip
            ax.imshow(seen, origin="lower", extent=extent, cmap="Greens", vmin=0, vmax=2.5,
                      interpolation="nearest")  # fmt: skip
        segs = world.obstacle_segments.reshape(-1, 2, 2)
        ax.add_collection(LineCollection(segs, colors="k", linewidths=0.8))
        pose = observation.true_pose
        if observation.scan is not None:
            pts = pose.transform_points(observation.scan.points())
            ax.plot(pts[:, 0], pts[:, 1], ".", color="tab:red", markersize=1.0)
        if goal is not None:
            ax.plot([goal.x], [goal.y], "*", color="tab:orange", markersize=12)
            ax.arrow(goal.x, goal.y, 0.5 * np.cos(goal.theta), 0.5 * np.sin(goal.theta),
                     color="tab:orange", width=0.05)  # fmt: skip
        ax.add_patch(_disc(pose, 0.25))
        ax.plot([pose.x, pose.x + 0.4 * np.cos(pose.theta)],
                [pose.y, pose.y + 0.4 * np.sin(pose.theta)], "-", color="tab:blue")  # fmt: skip
        ax.set_xlim(x0 - 0.5, x1 + 0.5)
        ax.set_ylim(y0 - 0.5, y1 + 0.5)
        ax.set_aspect("equal")
        fig.canvas.draw()
        image = np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()
        if self.human:
            import matplotlib.pyplot as plt

            plt.pause(0.001)
        return image

    def close(self) -> None:
        if self._fig is not None and self.human:
            import matplotlib.pyplot as plt

            plt.close(self._fig)
        self._fig = None


def _disc(pose: Pose, radius: float) -> Any:
    from matplotlib.patches import Circle

    return Circle((pose.x, pose.y), radius, facecolor="tab:blue", alpha=0.6)
