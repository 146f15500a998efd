"""Tiny on-disk images and datasets for tests (written with explicit seeds, never shipped data)."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
from PIL import Image

from ground.data.dataset import Dataset, DatasetBuilder
from ground.data.writer import write_dataset


def write_image(path: Path, width: int, height: int, seed: int = 0, fmt: str | None = None) -> Path:
    """A random RGB image of ``width`` x ``height`` at ``path`` (format from the suffix)."""
    rng = np.random.default_rng(seed)
    pixels = rng.integers(0, 256, size=(height, width, 3), dtype=np.uint8)
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(pixels).save(path, format=fmt)
    return path


def jpeg_bytes(width: int, height: int, seed: int = 0, orientation: int | None = None) -> bytes:
    rng = np.random.default_rng(seed)
    pixels = rng.integers(0, 256, size=(height, width, 3), dtype=np.uint8)
    buf = io.BytesIO()
    kwargs = {}
    if orientation is not None:
        exif = Image.Exif()
        exif[274] = orientation
        kwargs["exif"] = exif.tobytes()
    Image.fromarray(pixels).save(buf, "JPEG", quality=90, **kwargs)
    return buf.getvalue()


def smooth_jpeg(width: int, height: int, seed: int = 0, **save: object) -> bytes:
    """A JPEG of a smooth random image (a photo's statistics more than noise's); ``save``: Pillow JPEG options."""
    rng = np.random.default_rng(seed)
    small = rng.integers(0, 256, size=(max(height // 16, 2), max(width // 16, 2), 3), dtype=np.uint8)
    buf = io.BytesIO()
    Image.fromarray(small).resize((width, height), Image.BICUBIC).save(buf, "JPEG", quality=90, **save)
    return buf.getvalue()


def garbled_jpeg(width: int = 160, height: int = 120, seed: int = 0) -> bytes:
    """:func:`smooth_jpeg` with 64 bytes of its scan data, a third of the way in, overwritten by garbage that holds
    a marker (as a bad disk sector or network copy leaves it): libjpeg warns "Corrupt JPEG data: premature end of
    data segment" and OpenCV decodes the rest of the image as flat grey; the end-of-image marker is intact."""
    data = bytearray(smooth_jpeg(width, height, seed))
    scan = data.index(b"\xff\xda")
    at = scan + (len(data) - scan) // 3
    garbage = np.random.default_rng(seed).integers(0, 256, 64, dtype=np.uint8).tobytes()
    data[at : at + 64] = garbage[:20] + b"\xff\xd5" + garbage[22:]  # RST5 in a JPEG without restart markers
    return bytes(data)


def extraneous_jpeg(junk: bytes = b"\x00", before: bytes = b"\xff\xdb", seed: int = 0) -> tuple[bytes, bytes]:
    """(a JPEG encoded by OpenCV, the same with ``junk`` inserted before its first ``before`` marker): libjpeg skips
    the bytes, warning "Corrupt JPEG data: 1 extraneous bytes before marker 0xdb" on stderr, and decodes the same
    pixels."""
    clean = jpeg_bytes(64, 48, seed)
    at = clean.index(before)
    return clean, clean[:at] + junk + clean[at:]


def write_yolo_dataset(root: Path, names: tuple[str, ...] = ("fire", "smoke")) -> dict[str, list[list[float]]]:
    """A Roboflow-style YOLO folder (train/valid, data.yaml) with known rows; returns label rows per stem."""
    rows = {
        "a": [[0, 0.5, 0.5, 0.25, 0.5], [1, 0.2, 0.3, 0.1, 0.2]],
        "b": [[0, 0.125, 0.75, 0.25, 0.1]],
        "c": [],  # negative with an empty label file
    }
    layout = {"a": ("train", 64, 48), "b": ("train", 80, 40), "c": ("valid", 32, 32)}
    for stem, (split, w, h) in layout.items():
        write_image(root / split / "images" / f"{stem}.jpg", w, h, seed=len(stem) + w)
        label = root / split / "labels" / f"{stem}.txt"
        label.parent.mkdir(parents=True, exist_ok=True)
        label.write_text("".join(" ".join(f"{v:g}" for v in r) + "\n" for r in rows[stem]))
    write_image(root / "valid" / "images" / "d.png", 40, 30, seed=7)  # negative without a label file
    (root / "data.yaml").write_text(
        f"train: ../train/images\nval: ../valid/images\nnc: {len(names)}\nnames: [{', '.join(names)}]\n"
    )
    return rows


def planted_dataset(root: Path, gts: list, size: int = 100) -> Dataset:
    """A fire/smoke test set of ``size`` x ``size`` images: ``gts`` per image a list of (category id, xywh)
    (1 fire, 2 smoke); an empty list is a negative image."""
    builder = DatasetBuilder(root, ["fire", "smoke"])
    for k, boxes in enumerate(gts):
        image_id = builder.add_image(f"{k}.jpg", size, size, "real:x", "test")
        for cat, box in boxes:
            builder.add_box(image_id, ["fire", "smoke"][cat - 1], box)
    return builder.build({})


def tiny_pool(root: Path, n: int, source: str, category: str = "fire") -> Dataset:
    """``n`` tiny images on disk, each with one box, tagged ``source``."""
    builder = DatasetBuilder(root, [category])
    for i in range(n):
        write_image(root / f"img{i:03d}.png", 16, 12, seed=i)
        image_id = builder.add_image(f"img{i:03d}.png", 16, 12, source=source)
        builder.add_box(image_id, category, (1, 1, 4 + i % 5, 3))
    return builder.build()


def write_textured_room(path: Path, up: str = "+y", scale: float = 1.0, table: bool = True, walls: bool = True) -> Path:
    """A 6 x 3 x 6 m room as a glTF/GLB/OBJ file (by ``path``'s suffix): walls and ceiling of one inward-facing
    box, a 1 cm high floor quad with a striped base-colour texture (u, v repeat 4x), and a 1.2 x 0.8 x 1.2 m
    table box centred at (x, z) = (1.5, 1.5). Written with ``up`` (``+y`` or ``+z``) as the up axis and in
    units of ``1 / scale`` metres (``scale=0.01``: centimetres)."""
    import trimesh

    def solid(mesh: trimesh.Trimesh, rgba: tuple[int, int, int, int]) -> trimesh.Trimesh:
        material = trimesh.visual.material.PBRMaterial(baseColorFactor=rgba, metallicFactor=0.0, roughnessFactor=0.9)
        mesh.visual = trimesh.visual.TextureVisuals(material=material)
        return mesh

    scene = trimesh.Scene()
    if walls:
        room = trimesh.creation.box((6, 3, 6))
        room.invert()
        room.apply_translation((0, 1.5, 0))
        scene.add_geometry(solid(room, (200, 190, 170, 255)), "room")
    stripes = (np.indices((64, 64)).sum(0) // 8 % 2 * 180 + 40).astype(np.uint8)
    texture = Image.fromarray(np.dstack([stripes, stripes // 2, stripes // 4]))
    floor = trimesh.Trimesh(
        np.array([[-3, 0.01, -3], [3, 0.01, -3], [3, 0.01, 3], [-3, 0.01, 3]], float),
        np.array([[0, 2, 1], [0, 3, 2]]),
        process=False,
    )
    material = trimesh.visual.material.PBRMaterial(baseColorTexture=texture, metallicFactor=0.0, roughnessFactor=0.9)
    uv = np.array([[0, 0], [4, 0], [4, 4], [0, 4]], float)
    floor.visual = trimesh.visual.TextureVisuals(uv=uv, material=material)
    scene.add_geometry(floor, "floor")
    if table:
        box = trimesh.creation.box((1.2, 0.8, 1.2))
        box.apply_translation((1.5, 0.4, 1.5))
        scene.add_geometry(solid(box, (120, 70, 30, 255)), "table")
    frame = np.eye(4)
    if up == "+z":
        frame = trimesh.transformations.rotation_matrix(np.pi / 2, (1, 0, 0))  # file +Z = world +Y
    frame[:3, :3] /= scale
    scene.apply_transform(frame)
    path.parent.mkdir(parents=True, exist_ok=True)
    scene.export(path)
    return path


def _kit_part(path: Path, size: tuple[float, float, float], colour: tuple[int, int, int], door: int = 0) -> None:
    """A box of ``size`` (x, y, z kit units) standing on y = 0, centred in x and z, with a thin 'door' slab on its
    +Z (``door`` 1) or -Z (``door`` -1) face: the facade side, as the kit draws it."""
    import trimesh

    box = trimesh.creation.box(extents=size)
    box.apply_translation((0, size[1] / 2, 0))
    parts = [box]
    if door:
        slab = trimesh.creation.box(extents=(size[0] / 3, size[1] / 2, 0.02))
        slab.apply_translation((0, size[1] / 4, door * (size[2] / 2 + 0.01)))
        parts.append(slab)
    mesh = trimesh.util.concatenate(parts)
    mesh.visual.vertex_colors = np.tile([*colour, 255], (len(mesh.vertices), 1)).astype(np.uint8)
    path.parent.mkdir(parents=True, exist_ok=True)
    mesh.export(path)


def write_tiny_kits(root: Path) -> Path:
    """Two tiny building kits in ``root`` named like the Kenney kits' files: ``kenney_retro_urban/glb`` (facades
    face -Z, 1-unit wall blocks) and ``kenney_city_kit_suburban/glb`` (facades face +Z, roads in ``roads/``),
    each with a LICENSE.txt. Returns ``root``."""
    retro = root / "kenney_retro_urban" / "glb"
    for name, size, colour, door in [
        ("road-asphalt-center", (1, 0.004, 1), (40, 40, 45), 0),
        ("road-asphalt-side", (1, 0.05, 1), (120, 120, 115), 0),
        ("wall-a", (1, 1, 1), (150, 70, 50), 0),
        ("wall-a-door", (1, 1, 1), (150, 70, 50), -1),
        ("wall-a-window", (1, 1, 1), (140, 75, 55), -1),
        ("wall-a-garage", (1, 1, 1), (130, 80, 60), -1),
        ("detail-dumpster-closed", (0.6, 0.54, 0.45), (40, 90, 40), -1),
        ("detail-barrier-type-a", (0.44, 0.4, 0.14), (200, 200, 200), 0),
        ("tree-large", (0.3, 1.7, 0.3), (30, 110, 30), 0),
    ]:
        _kit_part(retro / f"{name}.glb", size, colour, door)
    suburban = root / "kenney_city_kit_suburban" / "glb"
    for name, size, colour, door in [
        ("roads/road-straight", (1, 0.02, 1), (70, 70, 80), 0),
        ("building-type-a", (1.3, 0.83, 1.0), (220, 220, 215), 1),
        ("building-type-b", (0.9, 1.1, 0.9), (210, 200, 190), 1),
        ("driveway-long", (0.36, 0.01, 0.4), (100, 100, 100), 0),
        ("fence", (0.48, 0.27, 0.08), (180, 110, 60), 0),
        ("tree-small", (0.2, 0.57, 0.2), (40, 140, 60), 0),
    ]:
        _kit_part(suburban / f"{name}.glb", size, colour, door)
    for kit in ("kenney_retro_urban", "kenney_city_kit_suburban"):
        (root / kit / "LICENSE.txt").write_text("License: (Creative Commons Zero, CC0)\n")
    return root


def write_frames(root: Path, n: int = 3, width: int = 128, height: int = 96, fire: tuple[int, int] = (20, 30)) -> Path:
    """A COCO dataset of ``n`` random ``width`` x ``height`` frames, frame k with k + 1 fire boxes ``fire`` (w, h)
    px at (4 + 30 j, 50) and one smoke box (2, 2, 30, 20); returns its folder."""
    src = root / "src"
    builder = DatasetBuilder(src, ["fire", "smoke"])
    for k in range(n):
        write_image(src / f"f{k}.png", width, height, seed=k)
        image = builder.add_image(f"f{k}.png", width, height, source="real:cams")
        for j in range(k + 1):
            builder.add_box(image, "fire", (4 + 30 * j, 50, *fire))
        builder.add_box(image, "smoke", (2, 2, 30, 20))
    write_dataset(builder.build(), root / "frames", ("coco",), "copy")
    return root / "frames"


def tiny_flames(count: int = 2, name: str = "f", **params: float) -> list:
    """``count`` tiny simulated flame sequences ``<name><k>`` (a 40 x 28 grid, 40 steps, one sprite kept every 20,
    sequence k from ``default_rng(k)``): the flame library of the synthesis tests; ``params`` are more
    :class:`synth.flames.simulate.FlameParams` (e.g. ``smoke=4.0, soot=1.2`` for smoky flames)."""
    from synth.flames import simulate

    p = simulate.FlameParams(rows=40, cols=28, frames=40, keep_every=20, warmup=30, **params)
    return [simulate.generate_sequence(f"{name}{k}", p, np.random.default_rng(k)) for k in range(count)]


def dataset_files(folder: Path) -> dict[str, bytes]:
    """Every file of a written dataset by relative path, with its bytes; ``manifest.json`` and ``data.yaml`` are left
    out (they name the output folder by absolute path): two runs that made the same dataset compare equal."""
    skip = {"manifest.json", "data.yaml"}
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file() and p.name not in skip}  # fmt: skip
