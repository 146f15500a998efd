"""Procedural streets laid out from modular building kits (:mod:`synth.kits`), rendered like any environment.

A street is a road of the kit's road tiles along +X, raised pavements on both sides, and on each side a row of
buildings with their facades to the road: City Kit Suburban houses behind front yards, with driveways (a
garage's forecourt), bins and fences in the gaps between them; or Retro Urban terraces of brick wall blocks
(ground floors of doors, shop windows and garage doors, upper floors of windows, awnings, balconies, roofs) on
the pavement, with alleys holding dumpsters. Street lights, construction barriers and trees stand on the
pavements and in the yards; bins, barriers, lights and trees come from any of the given kits. Daylight: a sun
of random elevation (12-65 degrees) whose colour temperature falls towards the horizon (3200 K low, 6500 K
high) and a blue sky light from above; the sky colour follows the sun.

Fires burn at building fronts, garages and bins: the layout records *fire zones* (rectangles of the ground
plane: the strip of pavement or yard in front of each facade, driveways, the ground around each bin, alleys),
and flames stand only on up-facing surfaces seen inside them (:func:`synth.standing.zone_mask`), sized in metres
like in the interiors.

Street ``k`` of a run seeded ``seed`` is laid out with ``default_rng([seed, 22, k])`` from the kit
``k % len(kits)`` (roads and buildings; props from every kit), so any street can be (re)made alone.

Frame: metres, +Y up, ground at y = 0, the road centred on z = 0 along x; side -1 is z < 0, side +1 is z > 0.
A rectangle ``Rect`` is ``(x0, x1, z0, z1)`` in metres.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import trimesh

from synth.camera import CameraRule
from synth.kits import Kit, Part, Pose, tinted
from synth.scenes import Environment, Light, _colour, add_box, translate

Rect = tuple[float, float, float, float]

FAMILY = "kit_street"
ZONE_DEPTH_M = 2.5  # depth of the fire zone in front of a facade, metres
BIN_ZONE_M = 1.5  # the fire zone reaches this far around a bin, metres
GROUND_M = 240.0  # side of the ground plane, metres (the horizon is far enough for a 5 m high camera)
ROAD_BEYOND_M = 30.0  # the road runs on this far past the last buildings, metres


@dataclass(frozen=True, eq=False)
class Placement:
    """A kit part at a (4, 4) part-to-world ``pose``, with the role it plays in the street."""

    role: str
    part: Part
    pose: Pose

    def rect(self) -> Rect:
        """(x0, x1, z0, z1) of the posed part's bounding box on the ground plane."""
        corners = trimesh.transform_points(trimesh.bounds.corners(self.part.bounds), self.pose)
        lo, hi = corners.min(0), corners.max(0)
        return float(lo[0]), float(hi[0]), float(lo[2]), float(hi[2])

    def front(self) -> np.ndarray:
        """(3,) world direction of the part's facade (its +Z)."""
        return self.pose[:3, :3] @ np.array([0.0, 0.0, 1.0])


@dataclass
class StreetLayout:
    """A street before rendering: the main kit, the street's ``length`` (buildings stand in |x| <= length / 2),
    the carriageway ``road_half`` (|z| below it holds road tiles only), the pavement's outer edge ``pavement``
    (|z|), its ``kerb`` height, the placements, fire ``zones`` and pavement ``slabs`` ((x, y, z) size, (x, y, z)
    bottom centre) in metres."""

    kit: Kit
    length: float
    road_half: float
    pavement: float
    kerb: float
    placements: list[Placement] = field(default_factory=list)
    zones: list[Rect] = field(default_factory=list)
    slabs: list[tuple[tuple[float, float, float], tuple[float, float, float]]] = field(default_factory=list)
    tinted: dict[tuple[str, str, int], Part] = field(default_factory=dict)  # tinted copies of parts, by tint

    def add(self, role: str, part: Part, pose: Pose) -> Placement:
        placement = Placement(role, part, pose)
        self.placements.append(placement)
        return placement

    def fits(self, rect: Rect) -> bool:
        """Whether ``rect`` stays off the carriageway and clear of every part placed so far (road tiles aside)."""
        if overlaps(rect, (-np.inf, np.inf, -self.road_half, self.road_half)):
            return False
        return not any(overlaps(rect, p.rect()) for p in self.placements if p.role != "road")

    def add_prop(self, role: str, part: Part, pose: Pose) -> Placement | None:
        """Place ``part`` when it :meth:`fits`; None otherwise."""
        placement = Placement(role, part, pose)
        if not self.fits(placement.rect()):
            return None
        self.placements.append(placement)
        return placement


def overlaps(a: Rect, b: Rect, eps: float = 1e-6) -> bool:
    """Whether two rectangles share more than an edge."""
    return a[0] < b[1] - eps and b[0] < a[1] - eps and a[2] < b[3] - eps and b[2] < a[3] - eps


def facing(part: Part, side: int, x_left: float, z_front: float, y: float = 0.0) -> Pose:
    """(4, 4) pose putting ``part`` with its x extent starting at ``x_left``, its facade (+Z face) on the line
    z = ``z_front`` and turned to face the road (towards z = 0), its bottom at ``y``."""
    yaw = 0.0 if side < 0 else 180.0
    x0, _, z0, z1 = Placement("", part, translate(0, 0, 0, yaw)).rect()
    facade = z1 if side < 0 else z0
    return translate(x_left - x0, y, z_front - facade, yaw)


def zone_before(x0: float, x1: float, z_front: float, side: int, depth: float) -> Rect:
    """The fire zone of a facade from x0 to x1 on the line z = ``z_front``: ``depth`` metres towards the road."""
    z_road = z_front - side * depth
    return x0, x1, min(z_front, z_road), max(z_front, z_road)


#: Mild colour casts (linear RGB factors on a part's base colour) a building is drawn with: white, cream, cool
#: grey-blue, pale yellow, rose, sage.
TINTS: tuple[tuple[float, float, float], ...] = (
    (1.0, 1.0, 1.0), (1.0, 0.93, 0.82), (0.88, 0.93, 1.0), (1.0, 0.97, 0.8), (0.97, 0.86, 0.84), (0.88, 0.94, 0.86)
)  # fmt: skip


def _tinted(street: StreetLayout, part: Part, tint: int) -> Part:
    """``part`` with colour cast ``TINTS[tint]`` (one copy per part and tint in a street, see :func:`tinted`)."""
    key = (part.name, part.kit, tint)
    if key not in street.tinted:
        street.tinted[key] = tinted(part, TINTS[tint])
    return street.tinted[key]


def _pick(kits: Sequence[Kit], main: Kit, role: str, rng: np.random.Generator) -> Part | None:
    """A random part of ``role`` from the main kit, else from any kit having it (None: no kit has it)."""
    parts = main.parts.get(role) or tuple(p for k in kits for p in k.parts.get(role, ()))
    return parts[int(rng.integers(len(parts)))] if parts else None


# -- the road -----------------------------------------------------------------------------------------------


def _tiles_along(street: StreetLayout, part: Part, z: float, yaw: float, extent: float) -> None:
    step = float(part.size[0])
    for x in np.arange(-extent + step / 2, extent, step):
        street.add("road", part, translate(float(x), 0.0, z, yaw))


def lay_road(kit: Kit, length: float, rng: np.random.Generator) -> StreetLayout:
    """The road of ``kit`` (tiles from -extent to +extent along x) and its pavements: a Suburban road tile spans
    the carriageway and kerbs, a 2.8-3.5 m pavement slab beside it; Retro Urban lays 1-2 asphalt tiles between
    two side tiles (asphalt inside, pavement outside) and 0-2.5 m more pavement."""
    extent = length / 2 + ROAD_BEYOND_M
    if "road_side" not in kit.parts:
        tile = kit.parts["road"][0]
        road_half, kerb, width = float(tile.size[2]) / 2, float(tile.size[1]), float(rng.uniform(2.8, 3.5))
        street = StreetLayout(kit, length, road_half, road_half + width, kerb)
        _tiles_along(street, tile, 0.0, 0.0, extent)
    else:
        centre, side = kit.parts["road"][0], kit.parts["road_side"][0]
        u, lanes = float(centre.size[2]), int(rng.integers(1, 3))
        road_half, kerb, width = lanes * u / 2 + u / 2, float(side.size[1]), float(rng.uniform(0.0, 2.5))
        street = StreetLayout(kit, length, road_half, road_half + u / 2 + width, kerb)
        for j in range(lanes):
            _tiles_along(street, centre, (j - (lanes - 1) / 2) * u, 0.0, extent)
        for s in (-1, 1):
            _tiles_along(street, side, s * (lanes * u / 2 + u / 2), 0.0 if s < 0 else 180.0, extent)
    if width > 0.01:
        for s in (-1, 1):
            at = (0.0, 0.0, s * (street.pavement - width / 2))
            street.slabs.append(((2 * extent, kerb, width), at))
    return street


# -- suburban houses ----------------------------------------------------------------------------------------


def _houses(street: StreetLayout, kits: Sequence[Kit], side: int, rng: np.random.Generator) -> None:
    """A row of houses behind 3-7 m front yards, 2.5-7 m apart; a yard tree now and then; in each gap a
    driveway (with a bin beside it) or a fence."""
    x, end = -street.length / 2 + float(rng.uniform(0, 3)), street.length / 2
    while True:
        house = _pick(kits, street.kit, "house", rng)
        if house is None or x + float(house.size[0]) > end:
            return
        width, depth = float(house.size[0]), float(house.size[2])
        setback = float(rng.uniform(3.0, 7.0))
        z_front = side * (street.pavement + setback)
        house = _tinted(street, house, int(rng.integers(len(TINTS))))
        street.add("house", house, facing(house, side, x, z_front))
        street.zones.append(zone_before(x + 0.3, x + width - 0.3, z_front, side, min(ZONE_DEPTH_M, setback)))
        tree = _pick(kits, street.kit, "tree", rng) if rng.random() < 0.5 else None
        if tree is not None and setback > 2.5:
            at = x + float(rng.uniform(0, max(width - tree.size[0], 0.1)))
            street.add_prop("tree", tree, facing(tree, side, at, side * (street.pavement + 0.3 + tree.size[2])))
        gap = float(rng.uniform(2.5, 7.0))
        _yard_gap(street, kits, (x + width, x + width + gap), z_front, depth, side, rng)
        x += width + gap


def _yard_gap(street, kits, span: tuple[float, float], z_front: float, depth: float, side: int, rng) -> None:
    """Between two houses: a driveway from the pavement to half the house depth (a fire zone, like a garage's
    forecourt) with a bin by the facade line, or a fence along the property line."""
    x0, x1 = span
    drive = street.kit.parts.get("driveway")
    if drive and x1 - x0 >= drive[0].size[0] + 0.4 and rng.random() < 0.65:
        tile, z = drive[0], side * street.pavement
        left = (x0 + x1) / 2 - float(tile.size[0]) / 2
        z_end = z_front + side * depth / 2
        while abs(z) < abs(z_end):
            street.add("driveway", tile, facing(tile, side, left, z + side * float(tile.size[2])))
            z += side * float(tile.size[2])
        street.zones.append(zone_before(left, left + float(tile.size[0]), z_front + side * depth / 2, side,
                                        abs(z_end) - street.pavement))  # fmt: skip
        _bin(street, kits, (x0, x1), z_front, side, rng)
        return
    fence = _pick(kits, street.kit, "fence", rng)
    if fence is None:
        return
    length = float(fence.size[0])
    for k in range(int(depth // length)):
        z = z_front + side * (k + 0.5) * length
        street.add_prop("fence", fence, translate((x0 + x1) / 2, 0.0, z, 90.0))


def _bin(street: StreetLayout, kits, span: tuple[float, float], z_front: float, side: int, rng) -> None:
    """A bin facing the road with its back on the line z = ``z_front``, somewhere in ``span`` (x) where it fits;
    the ground around it is a fire zone."""
    part = _pick(kits, street.kit, "bin", rng)
    if part is None:
        return
    for _ in range(4):
        x = float(rng.uniform(span[0], max(span[1] - part.size[0], span[0])))
        placed = street.add_prop("bin", part, facing(part, side, x, z_front - side * float(part.size[2])))
        if placed is not None:
            x0, x1, z0, z1 = placed.rect()
            street.zones.append((x0 - BIN_ZONE_M, x1 + BIN_ZONE_M, z0 - BIN_ZONE_M, z1 + BIN_ZONE_M))
            return


# -- retro urban terraces -----------------------------------------------------------------------------------


def _terraces(street: StreetLayout, kits: Sequence[Kit], side: int, rng: np.random.Generator) -> None:
    """A row of 2-5 block wide, 1-4 storey buildings with their facades on the pavement's outer edge, now and
    then an alley 3-6 m wide between two of them."""
    u = street.kit.profile.unit_m
    x, end, z_front = -street.length / 2, street.length / 2, side * street.pavement
    while x + 2 * u <= end:
        blocks = min(int(rng.integers(2, 6)), int((end - x) // u))
        _building(street, kits, x, blocks, z_front, side, rng)
        street.zones.append(zone_before(x, x + blocks * u, z_front, side, ZONE_DEPTH_M))
        x += blocks * u
        if rng.random() < 0.45:
            gap = float(rng.uniform(3.0, 6.0))
            _alley(street, kits, (x, x + gap), z_front, side, rng)
            x += gap


def _of_letter(parts: Sequence[Part], letter: str) -> Sequence[Part]:
    """The parts of one wall style (``wall-a-*``), or all of them when the style has none."""
    return [p for p in parts if p.name.startswith(f"wall-{letter}")] or parts


def _building(street: StreetLayout, kits, x: float, blocks: int, z_front: float, side: int, rng) -> None:
    """Wall blocks ``blocks`` wide: a ground floor of doors (at least one), windows, garage doors and plain
    walls with awnings over some, upper floors of windows and walls with balconies on some, a roof or not."""
    kit, u = street.kit, street.kit.profile.unit_m
    letter = "ab"[int(rng.integers(2))]
    floors = int(rng.integers(1, 5))
    ground = [str(rng.choice(["door", "window", "garage", "wall"], p=[0.3, 0.35, 0.15, 0.2])) for _ in range(blocks)]
    ground[int(rng.integers(blocks))] = "door"
    roof = kit.parts.get("roof") if rng.random() < 0.4 else None
    tint = int(rng.integers(len(TINTS)))
    for j in range(blocks):
        left = x + j * u
        for level in range(floors):
            role = ground[j] if level == 0 else ("window" if rng.random() < 0.75 else "wall")
            options = _of_letter(kit.parts.get(role) or kit.parts["wall"], letter)
            part = _tinted(street, options[int(rng.integers(len(options)))], tint)
            street.add("building", part, facing(part, side, left, z_front, level * u))
            _facade_detail(street, role, level, left, z_front, side, rng)
        if roof:
            part = _of_letter(roof, letter)[0]
            street.add("roof", part, facing(part, side, left, z_front, floors * u))
    if rng.random() < 0.3:
        _bin(street, kits, (x, x + blocks * u), z_front - side * 0.05, side, rng)


def _facade_detail(street: StreetLayout, role: str, level: int, left: float, z_front: float, side: int, rng) -> None:
    """An awning over a ground-floor door or window (40 %), a balcony under an upper window (25 %)."""
    kit, u = street.kit, street.kit.profile.unit_m
    kind = (
        "awning" if level == 0 and role in ("door", "window") else "balcony" if level > 0 and role == "window" else ""
    )
    if not kind or kind not in kit.parts or rng.random() > (0.4 if kind == "awning" else 0.25):
        return
    part = kit.parts[kind][int(rng.integers(len(kit.parts[kind])))]
    y = 0.5 * u if kind == "awning" else level * u
    at = left + (u - float(part.size[0])) / 2
    street.add("detail", part, facing(part, side, at, z_front - side * float(part.size[2]), y))


def _alley(street: StreetLayout, kits, span: tuple[float, float], z_front: float, side: int, rng) -> None:
    """An alley between two buildings: its ground up to 6 m behind the facade line is a fire zone; one or two
    dumpsters in it, a tree further back now and then."""
    x0, x1 = span
    street.zones.append(zone_before(x0, x1, z_front + side * 6.0, side, 6.0 + ZONE_DEPTH_M))
    for _ in range(int(rng.integers(1, 3))):
        _bin(street, kits, span, z_front + side * float(rng.uniform(1.5, 4.0)), side, rng)
    tree = _pick(kits, street.kit, "tree", rng) if rng.random() < 0.4 else None
    if tree is not None:
        street.add_prop("tree", tree, facing(tree, side, (x0 + x1 - tree.size[0]) / 2, z_front + side * 9.0))


# -- props along the pavements ------------------------------------------------------------------------------


def _pavement_props(street: StreetLayout, kits: Sequence[Kit], side: int, rng: np.random.Generator) -> None:
    """Street lights every 18-30 m on the pavement's outer edge, their arms over the pavement; a group of 2-4
    barriers or cones on the pavement now and then."""
    x = -street.length / 2 + float(rng.uniform(2, 10))
    while x < street.length / 2:
        light = _pick(kits, street.kit, "light", rng)
        if light is None:
            break
        lo, hi = float(light.bounds[0, 2]), float(light.bounds[1, 2])
        yaw = (0.0 if hi >= -lo else 180.0) + (0.0 if side < 0 else 180.0)  # the arm's side to the road
        z = side * (street.pavement - 0.4)
        street.add_prop("light", light, translate(x, 0.0, z, yaw))
        x += float(rng.uniform(18, 30))
    if rng.random() < 0.5:
        x = float(rng.uniform(-street.length / 2, street.length / 2))
        for k in range(int(rng.integers(2, 5))):
            part = _pick(kits, street.kit, "barrier", rng)
            if part is None:
                return
            z = side * (street.road_half + 0.3 + float(part.size[2]))
            street.add_prop("barrier", part, facing(part, side, x + k * (float(part.size[0]) + 0.3), z, street.kerb))


def lay_out_street(kits: Sequence[Kit], index: int, seed: int) -> StreetLayout:
    """Street ``index`` of a run seeded ``seed`` (module docstring): 50-80 m of buildings along the road."""
    if not kits:
        raise ValueError("no kits to lay out a street with")
    rng = np.random.default_rng([seed, 22, index])
    kit = kits[index % len(kits)]
    street = lay_road(kit, float(rng.uniform(50.0, 80.0)), rng)
    row = _houses if "house" in kit.parts else _terraces
    for side in (-1, 1):
        row(street, kits, side, rng)
        _pavement_props(street, kits, side, rng)
    return street


# -- the environment ----------------------------------------------------------------------------------------


def daylight(env: Environment, rng: np.random.Generator) -> None:
    """A sun of random azimuth and elevation (12-65 degrees), its colour temperature from 3200 K at the horizon
    to 6500 K above 47 degrees, a sky light from straight above (8000-12000 K), ambient light, and a sky colour
    from pale warm (low sun) to blue (high sun)."""
    elevation = float(rng.uniform(12.0, 65.0))
    high = min(1.0, (elevation - 12.0) / 35.0)
    kelvin = 3200.0 + 3300.0 * high + float(rng.normal(0.0, 200.0))
    sun = translate(0, 0, 0, float(rng.uniform(0.0, 360.0)), -elevation)
    env.lights.append(Light("directional", kelvin, float(rng.uniform(2.5, 4.0)), sun))
    env.lights.append(Light("directional", float(rng.uniform(8000, 12000)), float(rng.uniform(0.4, 0.9)),
                            translate(0, 0, 0, 0, -90)))  # fmt: skip
    env.ambient = float(rng.uniform(0.25, 0.4))
    warm, blue = np.array([0.74, 0.75, 0.78]), np.array([0.5, 0.68, 0.92])
    env.sky = _colour(rng, warm * (1.0 - high) + blue * high, 0.04)


def street_camera(street: StreetLayout) -> CameraRule:
    """A camera over the road and pavements 1.6-5 m up (a pedestrian to a pole-mounted CCTV), looking at the
    fire zones (their centres, 0.3 m up) with pitch up to 35 degrees."""
    half = street.length / 2
    targets = tuple(((z[0] + z[1]) / 2, 0.3, (z[2] + z[3]) / 2) for z in street.zones) or ((0.0, 0.3, 0.0),)
    reach = street.pavement - 0.5
    return CameraRule((-half + 5, half - 5, -reach, reach), (1.6, 5.0), targets, max_pitch_deg=35.0,
                      min_clearance=1.5, min_depth_spread=0.5, max_empty=0.7)  # fmt: skip


def street_environment(street: StreetLayout, index: int, seed: int) -> Environment:
    """The :class:`synth.scenes.Environment` of ``street``: the kit parts as file meshes (textures as the kit
    has them, buildings tinted), a flat ground (lawn green behind Suburban yards, grey behind Retro Urban
    terraces), pavement slabs, daylight, the camera rule and the fire zones."""
    rng = np.random.default_rng([seed, 22, index, 1])
    env = Environment(f"street-{index:03d}", FAMILY, street_camera(street), seed=seed)
    env.meshes = [(mesh, p.pose @ pose) for p in street.placements for mesh, pose in p.part.meshes]
    ground = (0.26, 0.4, 0.17) if "house" in street.kit.parts else (0.4, 0.39, 0.37)  # lawns, or waste ground
    add_box(env, (GROUND_M, 0.02, GROUND_M), (0.0, -0.04, 0.0), _colour(rng, ground, 0.03))
    paving = _colour(rng, (0.46, 0.46, 0.45), 0.04)
    for size, at in street.slabs:
        add_box(env, size, at, paving)
    env.zones = list(street.zones)
    daylight(env, rng)
    return env


def build_street(kits: Sequence[Kit], index: int, seed: int) -> Environment:
    """Street ``index`` of a run seeded ``seed`` as an environment (:func:`lay_out_street`)."""
    return street_environment(lay_out_street(kits, index, seed), index, seed)
