"""Camera views of the procedural environments, shared by Method 1 and Method 2.

Image ``i`` of a run with ``images_per_view`` images per view is on view ``i // images_per_view``; when that
view's kind (:func:`synth.places.kinds.kind_of_view`) is a photo, the image gets a photo background of its own
(:meth:`ViewCache.image_background`), so the images on photos use the photos one by one.

View ``v`` of a run seeded ``seed`` looks at environment ``v % scenes`` when all environments are procedural.
With mesh files (first, then the procedural environments) the ``views`` views of a run go to the environments in
equal consecutive blocks (``v * environments // views``), so each file scene is loaded, searched and kept in
memory once, then released. The camera is drawn by the environment's camera rules with ``default_rng([seed, 1,
v])`` (blocked views rejected), so a view can be (re)made alone: runs resume and are byte-reproducible.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from synth.places import camera, render, scenes
from synth.places.envfile import EnvironmentFile
from synth.places.kinds import kind_of_view, kind_weights
from synth.places.panorama import PanoramaBackgrounds
from synth.places.photos import PhotoBackgrounds
from synth.places.standing import standing_mask

MIN_ZONE_SHARE = 0.01  # with surfaces, a room view shows at least this share of pixels a flame may stand on


@dataclass(frozen=True)
class View:
    """One camera view: the environment, its pyrender scene (no camera node), the camera and the (H, W) float32
    depth of the scene's geometry seen from it (metres along the view axis, 0 = sky)."""

    env: scenes.Environment
    scene: Any
    camera: camera.CameraView
    depth: NDArray[np.float32]

    def meta(self) -> dict:
        return {"environment": self.env.name, "family": self.env.family, "camera": self.camera.to_json()}


def environment_index(view_index: int, files: int, scenes: int, views: int) -> int:
    """The environment view ``view_index`` of a run with ``views`` views looks at (module docstring): with mesh
    ``files``, equal consecutive blocks over the files and procedural ``scenes``; else ``view_index`` modulo the
    scenes."""
    total = files + scenes
    if not files:
        return view_index % total
    return min(view_index * total // views, total - 1)


class ViewCache:
    """Builds each environment's pyrender scene once and remembers the last view (and background) made."""

    def __init__(
        self,
        seed: int,
        scenes_count: int,
        renderer: render.Renderer,
        files: Sequence[EnvironmentFile] = (),
        photos: PhotoBackgrounds | None = None,
        photo_share: float = 0.5,
        views: int = 0,
        panoramas: PanoramaBackgrounds | None = None,
        panorama_share: float = 0.5,
        surfaces: bool = False,
    ) -> None:
        if scenes_count + len(files) < 1 and photos is None and panoramas is None:
            raise ValueError("at least one environment is needed")
        self.seed, self.scenes, self.renderer, self.files = seed, scenes_count, renderer, tuple(files)
        self.photos, self.panoramas, self.surfaces = photos, panoramas, surfaces
        renders = scenes_count + len(files)
        available = [k for k, there in (("photo", photos), ("panorama", panoramas), ("render", renders)) if there]
        self.weights = kind_weights(
            available, {"photo": photo_share, "panorama": panorama_share, "render": 1 - photo_share}
        )
        if self.files and views < 1:
            raise ValueError("with mesh files the number of views of the run is needed (views >= 1)")
        self.views = views
        self._scenes: dict[int, tuple[scenes.Environment, Any]] = {}
        self._view: View | None = None
        self._view_index = -1
        self._background: tuple[int, Any] | None = None
        self._photo_views = [0]  # _photo_views[v]: how many of views 0..v-1 show a photo (grown on demand)

    def environment_index(self, view_index: int) -> int:
        """The environment view ``view_index`` looks at (module docstring)."""
        return environment_index(view_index, len(self.files), self.scenes, self.views)

    def environment(self, env_index: int) -> tuple[scenes.Environment, Any]:
        """Environment ``env_index`` and its pyrender scene; a file scene replaces the previous one in memory."""
        if env_index not in self._scenes:
            loaded = len(self.files)  # one file scene in memory at a time
            if env_index < loaded:
                for old in [k for k in self._scenes if k < loaded]:
                    del self._scenes[old]
                self._scenes[env_index] = scenes.file_environment(self.files[env_index], self.renderer)
            else:
                env = scenes.build_environment(env_index - loaded, self.seed)
                self._scenes[env_index] = (env, scenes.to_pyrender(env, self.renderer.pyrender))
        return self._scenes[env_index]

    def view(self, view_index: int) -> View:
        """View ``view_index`` (see the module docstring); its depth is the accepted depth-only render."""
        if self._view is not None and self._view_index == view_index:
            return self._view
        env, scene = self.environment(self.environment_index(view_index))
        rng = np.random.default_rng([self.seed, 1, view_index])
        depths: list[NDArray[np.float32]] = []

        def depth_of(v: camera.CameraView) -> NDArray[np.float32]:
            depths.append(render.render_view(self.renderer, scene, v.pose, v.yfov, True)[1])
            return depths[-1]

        def shows_ground(v: camera.CameraView, depth: NDArray[np.float32]) -> bool:
            stand = self._stand_mask(v.pose, v.yfov, depth)
            return stand is None or float(stand.mean()) >= MIN_ZONE_SHARE

        cam = camera.find_view(env.camera, rng, depth_of, accept=shows_ground)
        self._view = View(env, scene, cam, depths[-1])
        self._view_index = view_index
        return self._view

    def _stand_mask(
        self, pose: NDArray[np.float64], yfov: float, depth: NDArray[np.float32]
    ) -> NDArray[np.bool_] | None:
        """(H, W) bool where a flame may stand in a render seen from ``pose`` with ``depth``: a room's up-facing
        surfaces with ``surfaces``; None: anywhere (the method's own rule)."""
        return standing_mask(depth, pose, yfov) if self.surfaces else None

    def image_background(self, image_index: int, per_view: int) -> tuple[NDArray[np.uint8], NDArray[np.float32], dict]:
        """The background of image ``image_index`` of a run with ``per_view`` images per view: that of its view
        ``image_index // per_view`` (:meth:`background`), except on a photo view, where every image has a photo
        view of its own, photo background :meth:`photo_index` (a crop is cheap, unlike a render): the images on
        photos go through the photos' order one by one, so a photo folder is used whole before any photo repeats.
        Depends only on (seed, kinds, ``image_index``, ``per_view``): the same in any process."""
        view = image_index // per_view
        kind = kind_of_view(self.seed, view, self.weights)
        if kind != "photo":
            return self.background(view)
        made = self.photos.background(self.photo_index(image_index, per_view))  # type: ignore[union-attr]
        if len(self.weights) > 1:
            made[2]["kind"] = kind
        return made

    def photo_index(self, image_index: int, per_view: int) -> int:
        """The rank of image ``image_index`` (on a photo view) among the run's images on photo views: every image
        of the photo views before its view, then its place in its own view."""
        view = image_index // per_view
        if len(self.weights) > 1:
            while len(self._photo_views) <= view:
                v = len(self._photo_views) - 1
                self._photo_views.append(self._photo_views[v] + (kind_of_view(self.seed, v, self.weights) == "photo"))
            before = self._photo_views[view]
        else:  # photos only: every view before is a photo view
            before = view
        return before * per_view + image_index - view * per_view

    def background(self, view_index: int) -> tuple[NDArray[np.uint8], NDArray[np.float32], dict]:
        """The background of view ``view_index``: ((H, W, 3) uint8 RGB, (H, W) float32 depth, metadata with its
        ``kind``), cached for reuse. Its kind is drawn by :func:`synth.places.kinds.kind_of_view` with the weights of the
        kinds there are: photos ``photo_share`` (:mod:`synth.places.photos`), panoramas ``panorama_share``
        (:mod:`synth.places.panorama`), renders ``1 - photo_share`` (with photos and renders only: a photo with
        probability ``photo_share``)."""
        if self._background and self._background[0] == view_index:
            return self._background[1]
        kind = kind_of_view(self.seed, view_index, self.weights)
        if kind == "photo":
            made = self.photos.background(view_index)  # type: ignore[union-attr]
        elif kind == "panorama":
            made = self.panoramas.background(view_index)  # type: ignore[union-attr]
        else:
            v = self.view(view_index)
            rgb, depth = render.render_view(self.renderer, v.scene, v.camera.pose, v.camera.yfov)
            made = (rgb, depth, v.meta())
            stand = self._stand_mask(v.camera.pose, v.camera.yfov, depth)
            if stand is not None:  # flames stand only there (a site, like a photo's ground)
                made = (rgb, np.where(stand, depth, np.float32(0)), {**made[2], "site": "surfaces", "people": []})
        if len(self.weights) > 1:
            made[2]["kind"] = kind
        self._background = (view_index, made)
        return made
