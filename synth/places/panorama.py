"""360° panoramas as Method 2 backgrounds: each view is a level pinhole camera standing in the captured place.

Frames. A panorama is an equirectangular (W, H) = (2N, N) image: column coordinate ``s`` in [0, W) is the yaw
``360 * s / W`` degrees (0 at the left edge, growing to the right, as when turning right), row coordinate ``t`` is
the elevation ``90 - 180 * t / H + horizon_offset`` degrees (the horizon at the middle row unless a sidecar says
otherwise); pixel ``i`` covers [i, i + 1). A view is a pinhole camera (:func:`synth.places.render.intrinsics`, pixel
centres at +0.5) with yaw, pitch (degrees, negative = looking down), vertical field of view and no roll. The
camera frame is x right, y down, z forward; the level world frame X right, Y down, Z forward at yaw 0.

Ground. The camera stands ``camera_height`` metres above flat ground: a ray below the horizon meets it, and the
view's depth is the z-depth (metres along the view axis) of that point, 0 where no flame may stand: at or above
the horizon, and ground farther than ``max_distance`` (horizontal, default :data:`MAX_GROUND_M`; indoors the
room's radius, so the walls' lower parts are not taken for floor). Views with less than :data:`MIN_GROUND` of
the image on such ground are redrawn.

Sidecars. ``NAME.yaml`` beside ``NAME.hdr`` and ``panoramas.yaml`` in its folder (for every panorama there; the
panorama's own file wins key by key) may set the keys of :class:`PanoramaSettings`.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import yaml
from numpy.typing import NDArray

from ground.config.loader import ConfigError, build_config
from ground.data.problems import Problem
from ground.data.walk import walk_files
from ground.image.imageio import MAX_PIXELS, ImageError, image_size, read_image
from synth.compose.light import REC709
from synth.places import render
from synth.schema import check_range

PANORAMA_SUFFIXES = (".jpg", ".jpeg", ".png", ".hdr", ".exr")
FLOAT_SUFFIXES = (".hdr", ".exr")
FOLDER_SIDECAR = "panoramas.yaml"
MAX_GROUND_M = 40.0  # default farthest ground (horizontal distance, metres) a flame may stand on
MIN_GROUND = 0.15  # least share of a view's pixels on usable ground
_RESOLUTION = re.compile(rb"-Y (\d+) \+X (\d+)")


@dataclass(frozen=True)
class PanoramaSettings:
    """What a sidecar may set (all optional; ranges are [lo, hi] drawn uniformly per view)."""

    camera_height: tuple[float, float] = (1.2, 3.0)  # metres above flat ground (CCTV-like)
    pitch: tuple[float, float] = (-20.0, 5.0)  # degrees, negative = looking down, in -89..89
    yfov: tuple[float, float] = (50.0, 75.0)  # vertical field of view, degrees, in 1..150
    yaw: tuple[float, float] = (0.0, 360.0)  # degrees (frame: module docstring); narrow it to avoid a wall
    horizon_offset: float = 0.0  # degrees the panorama's horizon lies below its middle row
    exposure: tuple[float, float] = (0.0, 0.0)  # EV offset of the tone-mapping key (HDR only)
    max_distance: float = MAX_GROUND_M  # metres: farthest ground a flame stands on (indoors: the room's radius)

    def __post_init__(self) -> None:
        check_range("camera_height", self.camera_height, 0.01)
        check_range("pitch", self.pitch, -89.0)
        check_range("yfov", self.yfov, 1.0)
        check_range("yaw", self.yaw)
        check_range("exposure", self.exposure)
        if self.pitch[1] > 89.0 or self.yfov[1] > 150.0 or self.yaw[1] - self.yaw[0] > 360.0:
            raise ValueError(f"pitch must lie in -89..89, yfov in 1..150 and yaw span <= 360 degrees: {self}")
        if abs(self.horizon_offset) > 45.0 or self.max_distance <= 0.0:
            raise ValueError(f"horizon_offset must lie in -45..45 degrees and max_distance be > 0: {self}")


def sidecars(panorama: Path) -> list[Path]:
    """The sidecar files that apply to ``panorama``: the folder's first, then its own (module docstring)."""
    found = [panorama.parent / FOLDER_SIDECAR, panorama.with_suffix(".yaml")]
    return [p for p in found if p.is_file()]


def read_settings(panorama: Path) -> PanoramaSettings:
    """The settings of ``panorama`` from its sidecars; unknown keys and wrong types raise ValueError naming the
    file and key."""
    merged: dict = {}
    for side in sidecars(panorama):
        try:
            raw = yaml.safe_load(side.read_text(encoding="utf-8")) or {}
            if not isinstance(raw, dict):
                raise ConfigError("a sidecar must be a mapping of keys")
            build_config(raw, PanoramaSettings)
        except (yaml.YAMLError, ConfigError, ValueError) as exc:
            raise ValueError(f"{side}: {exc}") from None
        merged.update(raw)
    return build_config(merged, PanoramaSettings)


def _hdr_size(path: Path) -> tuple[int, int]:
    """(width, height) from a Radiance header, or ImageError saying what is wrong with it."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(1 << 16)
    except OSError as exc:
        raise ImageError(path, f"cannot read ({exc.strerror or exc})") from None
    if not head.startswith((b"#?RADIANCE", b"#?RGBE")):
        raise ImageError(path, "Radiance HDR: no '#?RADIANCE' signature (not an .hdr file)")
    lines = head.split(b"\n")
    if b"" not in lines[1:-1]:
        raise ImageError(path, "Radiance HDR: the header never ends (truncated file?)")
    line = lines[lines.index(b"", 1) + 1].strip()
    match = _RESOLUTION.fullmatch(line)
    if not match or 0 in (int(match[1]), int(match[2])):
        raise ImageError(path, f"Radiance HDR: resolution line {line[:40]!r} is not '-Y H +X W'")
    return int(match[2]), int(match[1])


def read_panorama(path: Path) -> NDArray:
    """(H, W, 3) RGB: uint8 for 8-bit images, float32 linear light for .hdr/.exr; ImageError naming the reason."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in FLOAT_SUFFIXES:
        return read_image(path)
    kind = "Radiance HDR" if suffix == ".hdr" else "OpenEXR"
    if suffix == ".hdr" and np.prod(_hdr_size(path)) > MAX_PIXELS:
        raise ImageError(path, f"{kind}: over the {MAX_PIXELS / 1e6:g} MP decoding budget")
    try:
        img = cv2.imdecode(np.fromfile(path, np.uint8), cv2.IMREAD_ANYDEPTH | cv2.IMREAD_COLOR)
    except (cv2.error, OSError) as exc:
        raise ImageError(path, f"{kind}: cannot be decoded ({exc})") from None
    if img is None:
        why = "corrupt or truncated pixel data" if suffix == ".hdr" else "this OpenCV has no OpenEXR decoder"
        raise ImageError(path, f"{kind}: cannot be decoded ({why})")
    return np.clip(np.nan_to_num(img[:, :, ::-1].astype(np.float32), posinf=0.0), 0.0, None)


def panorama_size(path: Path) -> tuple[int, int]:
    """(width, height) of a panorama file, from its header where the format allows (.exr is decoded)."""
    suffix = Path(path).suffix.lower()
    if suffix == ".hdr":
        return _hdr_size(Path(path))
    if suffix == ".exr":
        h, w = read_panorama(Path(path)).shape[:2]
        return w, h
    return image_size(path)


def is_panorama(path: Path | str, min_width: int = 0) -> bool:
    """Whether ``path`` is an equirectangular panorama: a panorama suffix, aspect 2:1 (±1 %) and at least
    ``min_width`` pixels wide; ImageError when its header cannot be read."""
    if Path(path).suffix.lower() not in PANORAMA_SUFFIXES:
        return False
    w, h = panorama_size(Path(path))
    return abs(w / h - 2.0) <= 0.02 and w >= min_width


def readable_panorama(path: Path, problems: list[Problem] | None) -> bool:
    """:func:`is_panorama`, False for a file whose header cannot be read (appended to ``problems`` when given:
    path and reason)."""
    try:
        return is_panorama(path)
    except ImageError as exc:
        if problems is not None:
            problems.append(Problem(str(path), exc.reason))
        return False


def named_panorama(path: Path | str) -> bool:
    """:func:`is_panorama` of a file the user named: one that cannot be read is a ValueError naming it."""
    try:
        return is_panorama(path)
    except ImageError as exc:
        raise ValueError(str(exc)) from None


def list_panoramas(paths: Iterable[Path | str], problems: list[Problem] | None = None) -> list[Path]:
    """Panoramas under ``paths`` (files, or folders searched recursively where other images are skipped), sorted.
    A file in a folder whose header cannot be read is skipped and appended to ``problems`` (when given); a file
    given by name that cannot be read or is not a panorama is a ValueError naming it."""
    paths, found = list(paths), set()
    for item in paths:
        path = Path(item).absolute()
        if path.is_dir():
            files = walk_files(path, lambda n: n.lower().endswith(PANORAMA_SUFFIXES))
            found.update(p for p in files if readable_panorama(p, problems))
        elif not path.is_file():
            raise FileNotFoundError(f"{item}: no such file or folder")
        elif named_panorama(path):
            found.add(path)
        else:
            raise ValueError(f"{item}: not an equirectangular panorama (a 2:1 {'/'.join(PANORAMA_SUFFIXES)} image)")
    if not found:
        raise ValueError(f"no panoramas (2:1 images) in {', '.join(map(str, paths))}")
    return sorted(found, key=lambda p: p.as_posix())


def panorama_fingerprints(paths: Iterable[Path | str]) -> list[dict[str, str]]:
    """The panoramas under ``paths`` as name and sha256 of their bytes, and of their sidecars when present."""
    from ground.data.manifest import file_sha256

    out = []
    for p in list_panoramas(paths):
        entry = {"name": p.name, "sha256": file_sha256(p)}
        entry.update({f"sidecar {s.name}": file_sha256(s) for s in sidecars(p)})
        out.append(entry)
    return out


def camera_rays(width: int, height: int, yfov: float, cols: int, rows: int) -> tuple[NDArray, NDArray]:
    """(rows, cols) float64 ``x/z`` and ``y/z`` camera-frame ray slopes of a ``cols`` x ``rows`` grid of pixel
    centres spread over a ``width`` x ``height`` view of vertical field of view ``yfov`` radians."""
    fy = render.intrinsics(yfov, width, height)[1, 1]
    u = ((np.arange(cols) + 0.5) * width / cols - width / 2.0) / fy
    v = ((np.arange(rows) + 0.5) * height / rows - height / 2.0) / fy
    return np.meshgrid(u, v)


def _level(xn: NDArray, yn: NDArray, pitch: float) -> tuple[NDArray, NDArray, NDArray]:
    """Rays (x/z, y/z, 1) of a camera pitched by ``pitch`` radians in the level frame (X right, Y down, Z ahead)."""
    c, s = np.cos(pitch), np.sin(pitch)
    return xn, yn * c - s, yn * s + c


def ground_depth(
    width: int, height: int, yfov: float, pitch: float, camera_height: float, max_distance: float = MAX_GROUND_M
) -> NDArray[np.float32]:
    """(H, W) float32 z-depth in metres of the flat ground seen by each pixel; 0 at or above the horizon and for
    ground farther than ``max_distance`` metres (horizontal distance). Angles in radians."""
    x, down, ahead = _level(*camera_rays(width, height, yfov, width, height), pitch)
    z = camera_height / np.where(down > 1e-12, down, np.inf)  # the ray (x, y, 1) reaches the ground at z
    return np.where(z * np.hypot(x, ahead) <= max_distance, z, 0.0).astype(np.float32)


def panorama_maps(xn: NDArray, yn: NDArray, yaw: float, pitch: float, pano_size: tuple[int, int], offset: float):
    """cv2.remap (map_x, map_y) float32 panorama pixel coordinates of rays ``(xn, yn, 1)`` of a camera at ``yaw``,
    ``pitch`` (radians) in a ``pano_size`` (W, H) panorama whose horizon lies ``offset`` radians low."""
    pw, ph = pano_size
    x, down, ahead = _level(xn, yn, pitch)
    azimuth = yaw + np.arctan2(x, ahead)
    elevation = np.arctan2(-down, np.hypot(x, ahead))
    map_x = np.mod(azimuth / (2 * np.pi) * pw - 0.5, pw)
    map_y = np.clip((0.5 + (offset - elevation) / np.pi) * ph - 0.5, 0.0, ph - 1.0)
    return map_x.astype(np.float32), map_y.astype(np.float32)


def render_view(
    pano: NDArray, yaw: float, pitch: float, yfov: float, width: int, height: int, offset: float = 0.0
) -> tuple[NDArray, float]:
    """(H, W, C) perspective view of ``pano`` (dtype kept; angles in radians) and its softness: view pixels per
    degree / panorama pixels per degree. A view finer than the panorama (softness > 1) is sampled at the
    panorama's resolution and upscaled bilinearly."""
    ph, pw = pano.shape[:2]
    softness = (height / yfov) / (pw / (2 * np.pi))
    scale = min(1.0, 1.0 / softness)
    cols, rows = max(int(round(width * scale)), 1), max(int(round(height * scale)), 1)
    mx, my = panorama_maps(*camera_rays(width, height, yfov, cols, rows), yaw, pitch, (pw, ph), offset)
    view = cv2.remap(pano, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_WRAP)
    if (cols, rows) != (width, height):
        view = cv2.resize(view, (width, height), interpolation=cv2.INTER_LINEAR)
    return view, float(softness)


def tone_map(linear: NDArray[np.float32], key: float) -> tuple[NDArray[np.uint8], float]:
    """(H, W, 3) linear RGB -> uint8 sRGB: exposure mapping the log-average luminance to ``key`` (middle grey),
    extended Reinhard curve with white at the 99th luminance percentile (at least 1); and the exposure in EV."""
    lum = linear @ REC709
    delta = 1e-3 * float(lum.mean()) + 1e-12
    scale = key / float(np.exp(np.log(lum + delta).mean()))
    ls = lum * scale
    white2 = max(float(np.percentile(ls, 99.0)), 1.0) ** 2
    ratio = (1.0 + ls / white2) / (1.0 + ls) * scale  # display / linear luminance
    c = np.clip(linear * ratio[..., None], 0.0, 1.0)
    srgb = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)
    return (srgb * 255.0 + 0.5).astype(np.uint8), float(np.log2(scale))


class PanoramaBackgrounds:
    """Backgrounds from panoramas, the interface of :class:`synth.places.photos.PhotoBackgrounds`. View ``v`` looks into
    panorama ``order[v % n]``, ``order`` a permutation drawn by ``default_rng([seed, 8])`` (each panorama is used
    once before any repeats); its camera (and HDR exposure) is drawn by ``default_rng([seed, 7, v])``. Unreadable
    panoramas are skipped (the next in ``order`` is used) and named in :attr:`problems`."""

    def __init__(self, panoramas: Sequence[Path], width: int, height: int, seed: int, tries: int = 20) -> None:
        if not panoramas:
            raise ValueError("no panoramas")
        self.panoramas, self.width, self.height, self.seed = [Path(p) for p in panoramas], width, height, seed
        self.tries = tries
        self.order = np.random.default_rng([seed, 8]).permutation(len(self.panoramas))
        self.settings = [read_settings(p) for p in self.panoramas]  # sidecar errors now, not mid-run
        self.problems: dict[str, str] = {}
        self._loaded: tuple[Path, NDArray] | None = None

    def load(self, path: Path) -> NDArray:
        """Panorama ``path`` (:func:`read_panorama`); the last one loaded is kept in memory."""
        if self._loaded is None or self._loaded[0] != path:
            self._loaded = None  # release the previous one before decoding the next
            self._loaded = (path, read_panorama(path))
        return self._loaded[1]

    def background(self, view_index: int) -> tuple[NDArray[np.uint8], NDArray[np.float32], dict]:
        """((H, W, 3) uint8 RGB, (H, W) float32 ground z-depth (0 = no flame here), metadata) of view ``view_index``.

        Metadata: ``panorama`` (file name), ``yaw``, ``pitch`` (degrees), ``camera_height`` (metres), ``softness``,
        ``exposure`` (HDR only: log2 of the factor applied to linear radiance), ``camera.yfov`` (radians) and
        ``site: True``."""
        rng = np.random.default_rng([self.seed, 7, view_index])
        n = len(self.panoramas)
        for k in range(n):
            index = int(self.order[(view_index + k) % n])
            path = self.panoramas[index]
            if str(path) in self.problems:
                continue
            try:
                pano = self.load(path)
            except ImageError as exc:
                self.problems[str(path)] = str(exc)
                continue
            return self._view(path, pano, self.settings[index], rng)
        raise ValueError(f"none of the {n} panoramas can be read")

    def _view(self, path: Path, pano: NDArray, s: PanoramaSettings, rng: np.random.Generator):
        for _ in range(self.tries):
            yaw, pitch, yfov = (float(rng.uniform(*r)) for r in (s.yaw, s.pitch, s.yfov))
            height_m = float(rng.uniform(*s.camera_height))
            depth = ground_depth(self.width, self.height, *np.radians([yfov, pitch]), height_m, s.max_distance)
            if (depth > 0).mean() >= MIN_GROUND:
                break
        else:
            raise ValueError(
                f"{path.name}: no view in {self.tries} tries has ground within {s.max_distance:g} m on >= "
                f"{MIN_GROUND:.0%} of the image (pitch {list(s.pitch)}, yfov {list(s.yfov)} degrees, camera_height "
                f"{list(s.camera_height)} m): check its sidecar"
            )
        angles = np.radians([yaw % 360.0, pitch, yfov, s.horizon_offset])
        rgb, softness = render_view(pano, *angles[:3], self.width, self.height, angles[3])
        meta = {"panorama": path.name, "yaw": round(yaw % 360.0, 4), "pitch": round(pitch, 4)}
        meta |= {"camera_height": round(height_m, 4), "softness": round(softness, 4)}
        if rgb.dtype != np.uint8:
            rgb, ev = tone_map(rgb, float(rng.uniform(0.12, 0.25)) * 2.0 ** float(rng.uniform(*s.exposure)))
            meta["exposure"] = round(ev, 4)
        return rgb, depth, {**meta, "camera": {"yfov": float(np.radians(yfov))}, "site": True}
