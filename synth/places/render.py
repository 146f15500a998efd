"""Offscreen rendering with pyrender: EGL on Mesa's CPU renderer (llvmpipe) by default, OSMesa as fallback.

pyrender traps handled here, each with a test in ``tests/test_synth_places_render.py``:

1. pyrender 0.1.45 pins PyOpenGL 3.1.0 (its OSMesa import fails) and uses ``np.infty`` (gone in numpy 2):
   we depend on ``pyrender2`` (same ``pyrender`` module, PyOpenGL >= 3.1.9, numpy 2 clean).
2. pyrender keys compiled shader programs by ``OpenGL.contextdata.getContext()``; under OSMesa that returns a
   new ctypes pointer object on every call (equal hash, never equal), so the cache never hits and every draw
   compiles and leaks a program (RSS grows by GBs). :class:`Renderer` installs a cache keyed without the
   context (one renderer = one context).
3. An RGBA texture is not treated as transparent unless the material's base colour alpha < 1 (pyrender's
   texture transparency flag is never computed): :func:`rgba_material` sets ``BLEND`` and alpha 0.999.
4. Textures are flipped vertically on upload: image row 0 lands at ``v = 1``; :func:`textured_quad` puts
   ``v = 1`` at the top edge so images appear upright.
5. ``RenderFlags.SEG`` draws only the nodes in ``seg_node_map`` (unmapped geometry does not occlude):
   :meth:`Renderer.segment` maps every other mesh node to id 0.
6. RGB textures are uploaded with OpenGL's default 4-byte row alignment: a width whose ``3 * width`` is not a
   multiple of 4 shears the image into diagonal colour stripes. Textures made here are RGBA (always aligned).
7. EGL displays are per-device singletons: pyrender's ``delete`` calls ``eglTerminate``, which breaks every other
   open renderer of the process (``EGL_BAD_DISPLAY``). :meth:`Renderer.close` terminates only with the last one.
8. ``Scene.light_nodes`` is a set: lights reach the shader in hash (memory address) order, and with three or
   more lights the float sum of their contributions differs between runs. :func:`import_pyrender` makes it a
   list sorted by each light's type, pose, colour and intensity (Method 1 adds and removes flame lights image
   after image; ``test_same_seed_gives_byte_identical_output_and_resume_matches`` fails without this).

Coordinates: world +Y is up; a camera looks down its local -Z with +Y up (OpenGL / pyrender convention).
Images are (H, W, 3) uint8 RGB, row 0 at the top; depth is (H, W) float32 metres along the view axis, 0 where
nothing was drawn.
"""

from __future__ import annotations

import ctypes
import os
import sys
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from types import ModuleType
from typing import Any

import numpy as np
from numpy.typing import NDArray

PLATFORMS: tuple[str, ...] = ("egl", "osmesa")
#: Shared libraries each platform needs (Debian: libegl1 libegl-mesa0 libgbm1 libgl1-mesa-dri / libosmesa6).
_PLATFORM_LIBS: dict[str, tuple[str, ...]] = {
    "egl": ("libEGL.so.1",),
    "osmesa": ("libOSMesa.so.8", "libOSMesa.so.6", "libOSMesa.so"),
}
ENV_VAR = "FUZZYFIRE_GL"
INSTALL_HINT = "apt-get install -y libegl1 libegl-mesa0 libgbm1 libgl1-mesa-dri (EGL) or libosmesa6 (OSMesa)"


class RenderError(RuntimeError):
    """Offscreen OpenGL is not available or failed."""


def _loadable(names: tuple[str, ...]) -> bool:
    for name in names:
        try:
            ctypes.CDLL(name)
            return True
        except OSError:
            continue
    return False


def select_platform(requested: str | None = None) -> str:
    """The OpenGL platform to use: ``requested``, else ``$FUZZYFIRE_GL``, else ``$PYOPENGL_PLATFORM``, else the
    first of :data:`PLATFORMS` whose library loads. Raises :class:`RenderError` for an unknown or missing one."""
    name = requested or os.environ.get(ENV_VAR) or os.environ.get("PYOPENGL_PLATFORM")
    if name:
        if name not in PLATFORMS:
            raise RenderError(f"unknown OpenGL platform {name!r}; choose one of {', '.join(PLATFORMS)}")
        if not _loadable(_PLATFORM_LIBS[name]):
            raise RenderError(f"OpenGL platform {name!r}: {_PLATFORM_LIBS[name][0]} not found; {INSTALL_HINT}")
        return name
    for name in PLATFORMS:
        if _loadable(_PLATFORM_LIBS[name]):
            return name
    raise RenderError(f"no offscreen OpenGL library found; {INSTALL_HINT}")


def import_pyrender(platform: str | None = None) -> ModuleType:
    """Import pyrender bound to ``platform`` (chosen by :func:`select_platform`). PyOpenGL fixes its platform at
    first import, so a second, different request in the same process raises :class:`RenderError`."""
    name = select_platform(platform)
    current = os.environ.get("PYOPENGL_PLATFORM")
    if "OpenGL" in sys.modules and current != name:
        raise RenderError(f"PyOpenGL was already imported for platform {current!r}; cannot switch to {name!r}")
    os.environ["PYOPENGL_PLATFORM"] = name
    import pyrender

    if not getattr(pyrender.Scene, "_lights_sorted", False):  # trap 8
        pyrender.Scene.light_nodes = property(_sorted_light_nodes)
        pyrender.Scene._lights_sorted = True
    return pyrender


def _light_key(node: Any) -> tuple:
    light = node.light
    return (
        type(light).__name__,
        tuple(np.round(np.asarray(node.matrix, float), 9).ravel()),
        tuple(np.round(np.asarray(light.color, float), 9)),
        round(float(light.intensity), 9),
    )


def _sorted_light_nodes(scene: Any) -> list[Any]:
    """Every light node of ``scene`` in a run-independent order (trap 8)."""
    nodes = scene.point_light_nodes | scene.spot_light_nodes | scene.directional_light_nodes
    return sorted(nodes, key=_light_key)


def _stable_program_cache_class(pyrender: ModuleType) -> type:
    base = pyrender.shader_program.ShaderProgramCache

    class StableProgramCache(base):  # type: ignore[misc, valid-type]
        """Shader programs keyed by (shader names, defines) only: see trap 2 in the module docstring."""

        def __init__(self) -> None:
            super().__init__()
            self._stable: dict[Any, Any] = {}

        def get_program(self, vertex_shader, fragment_shader, geometry_shader=None, defines=None):  # noqa: ANN001
            names = tuple(os.path.basename(f) for f in (vertex_shader, fragment_shader, geometry_shader) if f)
            key = (names, tuple(sorted((defines or {}).items())))
            if key not in self._stable:
                self._stable[key] = super().get_program(vertex_shader, fragment_shader, geometry_shader, defines)
            return self._stable[key]

        def clear(self) -> None:
            super().clear()
            self._stable = {}

    return StableProgramCache


def ids_to_colors(ids: NDArray[np.integer]) -> NDArray[np.uint8]:
    """(N,) ids in [0, 2**24) -> (N, 3) uint8 colours (little-endian RGB)."""
    ids = np.asarray(ids, dtype=np.int64)
    if np.any((ids < 0) | (ids >= 1 << 24)):
        raise ValueError("segmentation ids must lie in [0, 2**24)")
    return np.stack([(ids >> s) & 255 for s in (0, 8, 16)], axis=-1).astype(np.uint8)


def colors_to_ids(rgb: NDArray[np.uint8]) -> NDArray[np.int32]:
    """(H, W, 3) uint8 -> (H, W) int32 ids (inverse of :func:`ids_to_colors`)."""
    c = rgb.astype(np.int32)
    return c[..., 0] | (c[..., 1] << 8) | (c[..., 2] << 16)


def _keep_egl_display(platform: Any) -> None:
    """Make pyrender's EGL platform destroy only its context on delete, not terminate the shared display."""

    def delete_context() -> None:
        from OpenGL.EGL import eglDestroyContext

        if platform._egl_display is not None and platform._egl_context is not None:
            eglDestroyContext(platform._egl_display, platform._egl_context)
        platform._egl_context = platform._egl_display = None

    platform.delete_context = delete_context


class Renderer:
    """One offscreen context of a fixed size. Use as a context manager or call :meth:`close`."""

    _live = 0  # open renderers in this process (trap 7)

    def __init__(self, width: int, height: int, platform: str | None = None) -> None:
        if width <= 0 or height <= 0:
            raise ValueError(f"render size must be positive, got {width}x{height}")
        self.pyrender = import_pyrender(platform)
        self.platform = os.environ["PYOPENGL_PLATFORM"]
        self.width, self.height = int(width), int(height)
        try:
            self._r = self.pyrender.OffscreenRenderer(self.width, self.height)
        except Exception as exc:  # pyrender raises bare exceptions from EGL/OSMesa setup
            raise RenderError(f"cannot create a {self.platform} context: {exc}; {INSTALL_HINT}") from exc
        Renderer._live += 1
        self._cache_cls = _stable_program_cache_class(self.pyrender)
        self._fix_program_cache()

    def _fix_program_cache(self) -> None:
        inner = self._r._renderer
        if not isinstance(inner._program_cache, self._cache_cls):
            inner._program_cache.clear()
            inner._program_cache = self._cache_cls()

    def color_depth(self, scene: Any) -> tuple[NDArray[np.uint8], NDArray[np.float32]]:
        """Render ``scene`` -> ((H, W, 3) uint8 RGB, (H, W) float32 depth in metres, 0 = nothing)."""
        self._fix_program_cache()
        color, depth = self._r.render(scene)
        return np.ascontiguousarray(color[..., :3]), np.ascontiguousarray(depth, dtype=np.float32)

    def depth(self, scene: Any) -> NDArray[np.float32]:
        """(H, W) float32 depth only (cheaper than :meth:`color_depth`)."""
        self._fix_program_cache()
        flags = self.pyrender.RenderFlags.DEPTH_ONLY
        return np.ascontiguousarray(self._r.render(scene, flags=flags), dtype=np.float32)

    def segment(self, scene: Any, ids: Mapping[Any, int]) -> NDArray[np.int32]:
        """(H, W) int32 map of node ids: ``ids`` maps mesh nodes to ids >= 1; every other mesh node of the scene
        is drawn as id 0 so it still occludes (trap 5). Meshes with ``is_visible = False`` are not drawn."""
        return self.segment_depth(scene, ids)[0]

    def segment_depth(self, scene: Any, ids: Mapping[Any, int]) -> tuple[NDArray[np.int32], NDArray[np.float32]]:
        """:meth:`segment` plus the (H, W) float32 depth of the drawn surfaces (metres, 0 = nothing)."""
        self._fix_program_cache()
        nodes = list(scene.mesh_nodes)
        values = np.array([ids.get(n, 0) for n in nodes], dtype=np.int64)
        colors = ids_to_colors(values)
        seg_map = {n: colors[i] for i, n in enumerate(nodes)}
        color, depth = self._r.render(scene, flags=self.pyrender.RenderFlags.SEG, seg_node_map=seg_map)
        return colors_to_ids(np.asarray(color)[..., :3]), np.ascontiguousarray(depth, dtype=np.float32)

    def close(self) -> None:
        if self._r is not None:
            Renderer._live -= 1
            if self.platform == "egl" and Renderer._live > 0:
                _keep_egl_display(self._r._platform)  # trap 7
            self._r.delete()
            self._r = None

    def __enter__(self) -> Renderer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def rgba_opaque(rgba: NDArray[np.uint8]) -> NDArray[np.uint8]:
    """(h, w, 4) uint8 copy with alpha 255 (an emissive map: colour only, in 4 channels, see trap 6)."""
    out = np.array(rgba, dtype=np.uint8, copy=True)
    out[..., 3] = 255
    return out


def rgba_material(pyrender: ModuleType, rgba: NDArray[np.uint8], emissive: bool = True) -> Any:
    """A material showing an (h, w, 4) uint8 RGBA image with its alpha (trap 3). ``emissive``: the colour is
    emitted (unlit, shown as is) rather than lit."""
    if rgba.ndim != 3 or rgba.shape[2] != 4 or rgba.dtype != np.uint8:
        raise ValueError(f"rgba must be (h, w, 4) uint8, got {rgba.shape} {rgba.dtype}")
    tex = pyrender.Texture(source=rgba, source_channels="RGBA")
    if emissive:
        emit = pyrender.Texture(source=rgba_opaque(rgba), source_channels="RGBA")  # trap 6: RGBA keeps rows aligned
        return pyrender.MetallicRoughnessMaterial(
            baseColorFactor=(0.0, 0.0, 0.0, 0.999),
            baseColorTexture=tex,
            emissiveTexture=emit,
            emissiveFactor=(1.0, 1.0, 1.0),
            metallicFactor=0.0,
            roughnessFactor=1.0,
            alphaMode="BLEND",
            doubleSided=True,
        )
    return pyrender.MetallicRoughnessMaterial(
        baseColorFactor=(1.0, 1.0, 1.0, 0.999),
        baseColorTexture=tex,
        metallicFactor=0.0,
        roughnessFactor=1.0,
        alphaMode="BLEND",
        doubleSided=True,
    )


def quad_corners(width: float, height: float) -> NDArray[np.float64]:
    """(4, 3) corners of a quad in its local frame (x right, y up, facing +Z), centred at the bottom edge:
    top-left, top-right, bottom-right, bottom-left."""
    w2 = width / 2.0
    return np.array([[-w2, height, 0], [w2, height, 0], [w2, 0, 0], [-w2, 0, 0]], dtype=np.float64)


def textured_quad(pyrender: ModuleType, width: float, height: float, material: Any, uv_scale: tuple = (1, 1)) -> Any:
    """A pyrender mesh of one quad (see :func:`quad_corners`) whose texture appears upright (trap 4):
    image row 0 at the top edge. ``uv_scale`` repeats the texture (u, v) times."""
    pos = quad_corners(width, height).astype(np.float32)
    su, sv = uv_scale
    uv = np.array([[0, sv], [su, sv], [su, 0], [0, 0]], dtype=np.float32)
    normals = np.tile(np.array([[0, 0, 1]], dtype=np.float32), (4, 1))
    faces = np.array([[0, 2, 1], [0, 3, 2]], dtype=np.uint32)
    prim = pyrender.Primitive(positions=pos, normals=normals, texcoord_0=uv, indices=faces, material=material)
    return pyrender.Mesh(primitives=[prim])


def look_at(eye: NDArray[np.float64], target: NDArray[np.float64], up=(0.0, 1.0, 0.0)) -> NDArray[np.float64]:
    """(4, 4) camera-to-world pose at ``eye`` looking at ``target`` (camera -Z forward, +Y up)."""
    eye, target = np.asarray(eye, float), np.asarray(target, float)
    forward = target - eye
    norm = np.linalg.norm(forward)
    if norm < 1e-9:
        raise ValueError("eye and target coincide")
    z = -forward / norm
    x = np.cross(np.asarray(up, float), z)
    if np.linalg.norm(x) < 1e-9:
        raise ValueError("view direction is parallel to up")
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    pose = np.eye(4)
    pose[:3, 0], pose[:3, 1], pose[:3, 2], pose[:3, 3] = x, y, z, eye
    return pose


def intrinsics(yfov: float, width: int, height: int) -> NDArray[np.float64]:
    """(3, 3) pinhole matrix of a pyrender ``PerspectiveCamera(yfov)`` rendered at ``width`` x ``height``
    (pixel centres at +0.5; aspect = width / height)."""
    fy = height / (2.0 * np.tan(yfov / 2.0))
    return np.array([[fy, 0, width / 2.0], [0, fy, height / 2.0], [0, 0, 1.0]])


def project(points: NDArray[np.float64], pose: NDArray[np.float64], k: NDArray[np.float64]) -> NDArray[np.float64]:
    """(N, 3) world points -> (N, 3) ``(u, v, depth)``: pixel coords (row 0 at the top) and depth along the view
    axis (> 0 in front of the camera) for camera-to-world ``pose`` and intrinsics ``k``."""
    world_to_cam = np.linalg.inv(pose)
    pc = (world_to_cam[:3, :3] @ np.asarray(points, float).T).T + world_to_cam[:3, 3]
    depth = -pc[:, 2]
    safe = np.where(np.abs(depth) < 1e-9, 1e-9, depth)
    u = k[0, 0] * pc[:, 0] / safe + k[0, 2]
    v = -k[1, 1] * pc[:, 1] / safe + k[1, 2]
    return np.stack([u, v, depth], axis=1)


def unproject(uv: NDArray[np.float64], depth: NDArray[np.float64], pose, k: NDArray[np.float64]) -> NDArray[np.float64]:
    """Inverse of :func:`project`: (N, 2) pixel coords (row 0 at the top) and (N,) depths along the view axis ->
    (N, 3) world points, for camera-to-world ``pose`` (4, 4) and intrinsics ``k`` (3, 3)."""
    uv, d = np.asarray(uv, float).reshape(-1, 2), np.asarray(depth, float).reshape(-1)
    pc = np.stack([(uv[:, 0] - k[0, 2]) / k[0, 0] * d, -(uv[:, 1] - k[1, 2]) / k[1, 1] * d, -d], axis=1)
    return (np.asarray(pose, float)[:3, :3] @ pc.T).T + np.asarray(pose, float)[:3, 3]


@contextmanager
def camera_at(renderer: Renderer, scene: Any, pose: NDArray[np.float64], yfov: float) -> Iterator[Any]:
    """Context in which ``scene`` has a perspective camera at ``pose`` (4, 4) with vertical field of view ``yfov``
    (radians, aspect of the renderer); the camera node is removed again on exit."""
    pr = renderer.pyrender
    cam = pr.PerspectiveCamera(yfov=yfov, aspectRatio=renderer.width / renderer.height, znear=0.05, zfar=200.0)
    node = scene.add(cam, pose=pose)
    try:
        yield node
    finally:
        scene.remove_node(node)


def render_view(
    renderer: Renderer, scene: Any, pose: NDArray[np.float64], yfov: float, depth_only: bool = False
) -> tuple[NDArray[np.uint8] | None, NDArray[np.float32]]:
    """Render ``scene`` from a camera at ``pose`` (4, 4) with vertical field of view ``yfov`` (radians); the
    camera node is removed again. Returns (RGB or None when ``depth_only``, depth)."""
    with camera_at(renderer, scene, pose, yfov):
        if depth_only:
            return None, renderer.depth(scene)
        return renderer.color_depth(scene)
