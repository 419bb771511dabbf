"""``flic view``: an interactive 3D viewer of the clusters (polyscope), and its screenshots.

Points are coloured by cluster (the colours of ``--export ply`` and ``--render``,
:func:`flic_cli.io.ply.cluster_rgb`), the ground the remover took light grey, unclustered
points dark grey. Where the data has labels, the ground truth lies beside the prediction (to its
right, as seen from above; forward = +x points right in the image): a ground-truth object takes
the colour of the cluster that found it (the paper's matching,
:func:`flic_cli.plots.object_marks`), a missed object a colour of its own.
The window has a frame slider, previous / next buttons and a method menu; ``--screenshot``
renders the first selected frame from above into a PNG without a window (polyscope's EGL
backend: no display needed, Mesa's software renderer is enough).

polyscope is an optional extra: ``pip install 'flic[viewer]'``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from flic_cli.errors import FlicInputError

#: Background (black, so that the light grey ground and dark grey points both show).
BACKGROUND = (0.0, 0.0, 0.0)
#: Gap between the prediction and the ground truth beside it, metres.
GAP_M = 4.0
#: Half-width of the square around the sensor that is drawn, metres (as ``--render``).
EXTENT_M = 40.0


def polyscope() -> Any:
    """The polyscope module, or a one-line install hint."""
    try:
        import polyscope as ps
    except ImportError:
        raise FlicInputError(
            None, "flic view needs polyscope: pip install 'flic[viewer]'"
        ) from None
    return ps


@dataclass
class ViewFrame:
    """One segmented frame, ready to draw.

    Attributes
    ----------
    points : (N, 3) float32 points in metres (sensor frame), those within :data:`EXTENT_M`
        of the sensor in x and y.
    pred_rgb : (N, 3) float64 colours of the prediction, in [0, 1].
    gt_rgb : (N, 3) colours of the ground truth, or None without labels.
    clusters : number of clusters.
    title : what the window shows about the frame.
    """

    points: np.ndarray
    pred_rgb: np.ndarray
    gt_rgb: np.ndarray | None
    clusters: int
    title: str


def colours(
    pred: np.ndarray, ground: np.ndarray, gt_labels: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray | None]:
    """Colours of the prediction and of the ground truth (as ``--render`` draws them).

    Parameters
    ----------
    pred : (N,) cluster ids (<= 0: none).
    ground : (N,) bool, the points the ground remover took.
    gt_labels : (N,) uint32 SemanticKITTI labels, or None.

    Returns
    -------
    pred_rgb, gt_rgb : (N, 3) float64 in [0, 1]; gt_rgb None without labels.
    """
    from flic_cli.classes import ground_mask, thing_mask
    from flic_cli.io.ply import cluster_rgb
    from flic_cli.plots import VIEW_GROUND, VIEW_OTHER, object_marks

    p = np.asarray(pred).astype(np.int64)
    rgb = cluster_rgb(np.maximum(p, 0)).astype(np.float64) / 255
    rgb[p <= 0] = VIEW_OTHER
    rgb[np.asarray(ground, dtype=bool)] = VIEW_GROUND
    if gt_labels is None:
        return rgb, None
    gt = np.asarray(gt_labels).astype(np.uint32)
    m = object_marks(gt, p).matches
    gt_rgb = np.tile(np.array(VIEW_OTHER, dtype=np.float64), (p.size, 1))
    gt_rgb[ground_mask(gt)] = VIEW_GROUND
    is_obj = thing_mask(gt) & np.isin(gt, m.label)
    obj_index = np.searchsorted(m.label, gt)
    colour_ids = np.where(m.cluster >= 0, m.cluster, 1_000_003 + np.arange(len(m)))
    gt_rgb[is_obj] = cluster_rgb(colour_ids[obj_index[is_obj]]).astype(np.float64) / 255
    return rgb, gt_rgb


class Viewer:
    """The frames of a dataset segmented by one of several methods, drawn with polyscope.

    Parameters
    ----------
    data : the dataset path (any format flic reads).
    methods : method variants the menu offers; the first is shown.
    frames : ``(start, stop)`` frame selection, or None.
    sequences : sequences (or bag topics), or None.
    config : a loaded :class:`flic_cli.config.Config`.
    ground_remover : as for ``flic segment``.
    """

    def __init__(
        self,
        data: Path,
        methods: list[str],
        frames: tuple[int | None, int | None] | None,
        sequences: list[str] | None,
        config: Any,
        ground_remover: str = "own",
    ) -> None:
        from flic_cli.io import open_dataset
        from flic_cli.runs.pipeline import build_segmenter

        self.ds = open_dataset(data, sequences, frames)
        self.refs = self.ds.refs()
        self.config = config
        self.methods = list(methods)
        self.segmenters = {m: build_segmenter(config, m, "ground", ground_remover) for m in methods}
        self.method = self.methods[0]
        self.index = 0
        self._cache: dict[tuple[str, int], ViewFrame] = {}
        self._ps: Any = None

    def frame(self, index: int, method: str) -> ViewFrame:
        """Frame ``index`` of the selection segmented by ``method`` (computed once)."""
        from flic_cli.runs.pipeline import prepare

        key = (method, index)
        if key not in self._cache:
            ref = self.refs[index]
            prep = prepare(self.ds.load(ref), "ground", self.config.projection)
            labels, ground = self.segmenters[method].run(prep.image, prep.points)
            on_ground = np.zeros(labels.shape[0], bool) if ground is None else ground.on_ground
            pred_rgb, gt_rgb = colours(labels, on_ground, prep.labels)
            clusters = int(np.unique(labels[labels > 0]).size)
            near = (np.abs(prep.points[:, :2]) <= EXTENT_M).all(axis=1)
            pred_rgb = pred_rgb[near]
            gt_rgb = None if gt_rgb is None else gt_rgb[near]
            title = f"{ref.sequence} frame {ref.frame}: {method}, {clusters} clusters"
            self._cache = {k: v for k, v in self._cache.items() if abs(k[1] - index) < 3}
            self._cache[key] = ViewFrame(prep.points[near], pred_rgb, gt_rgb, clusters, title)
        return self._cache[key]

    # -- drawing -----------------------------------------------------------------------------

    def init(self, headless: bool) -> None:
        """Start polyscope (EGL without a window when ``headless``)."""
        ps = polyscope()
        if ps.is_initialized():  # one polyscope per process (a second Viewer reuses it)
            pass
        elif headless:
            ps.set_use_prefs_file(False)  # no imgui.ini / .polyscope.ini in the working folder
            ps.set_allow_headless_backends(True)
            try:
                ps.init("openGL3_egl")
            except Exception as exc:  # polyscope raises RuntimeError or its own errors
                raise FlicInputError(
                    None, f"cannot render without a window here (polyscope EGL: {exc})"
                ) from None
        else:
            ps.set_use_prefs_file(False)
            ps.init()
        ps.set_program_name("flic view")
        ps.set_ground_plane_mode("none")
        ps.set_background_color(BACKGROUND)
        ps.set_SSAA_factor(1)
        if headless:
            ps.set_window_size(1600, 800)
        self._ps = ps

    def draw(self) -> ViewFrame:
        """Draw the current frame and method (prediction, and the ground truth beside it)."""
        ps = self._ps
        vf = self.frame(self.index, self.method)
        ps.remove_all_structures()
        radius = 0.0009 if vf.points.shape[0] > 60_000 else 0.0013
        cloud = ps.register_point_cloud(
            "prediction", vf.points, radius=radius, point_render_mode="quad", material="flat"
        )
        cloud.add_color_quantity("cluster", vf.pred_rgb, enabled=True)
        if vf.gt_rgb is not None:
            shifted = vf.points + np.array([2 * EXTENT_M + GAP_M, 0.0, 0.0], np.float32)
            gt = ps.register_point_cloud(
                "ground truth", shifted, radius=radius, point_render_mode="quad", material="flat"
            )
            gt.add_color_quantity("object", vf.gt_rgb, enabled=True)
        return vf

    def top_view(self, aspect: float = 2.0, fov_deg: float = 45.0) -> None:
        """The camera straight above the drawn points, looking down, far enough for all of
        them to fit (perspective, vertical field of view ``fov_deg``, image ``aspect`` =
        width / height); forward (+x) to the right of the image, left (+y) up."""
        ps = self._ps
        pts = [self.frame(self.index, self.method).points]
        lo = pts[0].min(axis=0).astype(np.float64) if pts[0].size else np.zeros(3)
        hi = pts[0].max(axis=0).astype(np.float64) if pts[0].size else np.ones(3)
        if self.frame(self.index, self.method).gt_rgb is not None:
            hi[0] += 2 * EXTENT_M + GAP_M
        centre = (lo + hi) / 2
        t = np.tan(np.radians(fov_deg) / 2)
        dist = 1.02 * max((hi[0] - lo[0]) / 2 / (aspect * t), (hi[1] - lo[1]) / 2 / t)
        ps.set_view_projection_mode("perspective")
        ps.set_vertical_fov_degrees(fov_deg)
        ps.set_up_dir("y_up")  # the image's up: +y (z_up would be collinear with the view)
        ps.look_at(
            (float(centre[0]), float(centre[1]), float(hi[2]) + dist),
            (float(centre[0]), float(centre[1]), 0.0),
        )

    def screenshot(self, path: Path) -> ViewFrame:
        """Render the current frame from above into ``path`` (PNG, written atomically)."""
        from flic_cli.io.atomic import atomic_write

        vf = self.draw()
        self.top_view()
        path = Path(path)
        with atomic_write(path) as tmp:
            png = tmp.with_name(tmp.name + ".png")  # polyscope picks the format by suffix
            self._ps.screenshot(str(png), transparent_bg=False)
            png.replace(tmp)
        return vf

    def show(self) -> None:
        """The interactive window: frame slider, previous / next, method menu."""
        ps = self._ps
        gui = ps.imgui
        self.draw()
        ps.set_up_dir("z_up")  # turntable navigation about the vertical
        ps.set_view_projection_mode("perspective")
        ps.look_at((-0.6 * EXTENT_M, 0.0, 0.5 * EXTENT_M), (0.3 * EXTENT_M, 0.0, 0.0))

        def callback() -> None:
            vf = self.frame(self.index, self.method)
            gui.TextUnformatted(vf.title)
            changed, value = gui.SliderInt("frame", self.index, 0, len(self.refs) - 1)
            step = 0
            if gui.Button("previous"):
                step = -1
            gui.SameLine()
            if gui.Button("next"):
                step = 1
            new = int(np.clip((value if changed else self.index) + step, 0, len(self.refs) - 1))
            method = self.method
            if gui.BeginCombo("method", self.method):
                for m in self.methods:
                    if gui.Selectable(m, m == self.method)[0]:
                        method = m
                gui.EndCombo()
            if new != self.index or method != self.method:
                self.index, self.method = new, method
                self.draw()

        ps.set_user_callback(callback)
        ps.show()
