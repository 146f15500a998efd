"""Real fires of several boxes, pasted whole (``flames.cutout_groups``).

Annotators box a burning building window by window and a spreading fire patch by patch: 35 % of the fire boxes
of the shared curated set sit in images with five or more of them (``fuzzyfire stats``: crowding), and a detector
trained on single pasted flames merges such fires into one box or misses their small patches. With
``cutout_groups`` a real cut-out drawn for a flame comes with the other cut-outs of its source image
(:func:`synth.library.cutout_library`'s ``origins``), each moved and scaled with it so that the group keeps the
layout and relative sizes it had in its image; each member is a placement of its own, so it keeps its own box. Nothing is drawn from an rng: the pool's other draws (places,
flames, looks) stay those of the same pool without groups.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace

from synth.composite import Placement
from synth.library import Origin, is_cutout
from synth.sprites import Sprite, SpriteSequence

#: A cut-out sprite of the library: its name ``"<sequence>/<frame>"``, the sprite, where it sat in its image.
Member = tuple[str, Sprite, Origin]

#: A group is shrunk (about its anchor's base) until it spans at most this share of the image's height and width.
FIT = 0.6


def group_index(library: Sequence[SpriteSequence]) -> dict[str, list[Member]]:
    """``"<sequence>/<frame>"`` of each real cut-out of ``library`` whose origin is known -> every such cut-out of
    its source image (itself included), in ``library`` order."""
    by_image: dict[str, list[Member]] = {}
    for seq in library:
        if not is_cutout(seq):
            continue
        for frame, (sprite, origin) in enumerate(zip(seq.sprites, seq.meta.get("origins", ()), strict=False)):
            if origin is not None:
                by_image.setdefault(origin[0], []).append((f"{seq.name}/{frame}", sprite, origin))
    return {name: group for group in by_image.values() for name, _, _ in group}


def grouped(
    anchor: Placement, name: str, index: Mapping[str, Sequence[Member]], width: int, height: int
) -> list[tuple[Placement, str]]:
    """``anchor`` (``name`` = its ``"<sequence>/<frame>"``) and the other members of its group (:func:`group_index`)
    as placements in a ``width`` x ``height`` image, anchor first: each member's top-left at the anchor's plus its
    offset in the source image times the anchor's scale (image pixels per source pixel, per axis), its size its own
    times that scale, with the anchor's blend, glow, opacity and look. A group is never drawn larger than it was in
    its source image (upscaling blurs, and that is how large that fire was in a frame), nor spanning more than
    :data:`FIT` of the image's height or width: the scale (anchor included) shrinks about the anchor's base.
    Members under 2 px on a side or wholly outside the image are left out; an anchor that is no cut-out of a known
    image, or alone in it, comes back as it is."""
    members = index.get(name, ())
    if len(members) < 2:
        return [(anchor, name)]
    (aw, ah), (_, ax, ay) = anchor.sprite.size, next(origin for n, _, origin in members if n == name)
    sx, sy = anchor.width / aw, anchor.height / ah
    x0, y0 = min(o[1] for _, _, o in members), min(o[2] for _, _, o in members)
    x1 = max(o[1] + s.size[0] for _, s, o in members)
    y1 = max(o[2] + s.size[1] for _, s, o in members)
    k = min(1.0, 1.0 / max(sx, sy), FIT * width / ((x1 - x0) * sx), FIT * height / ((y1 - y0) * sy))
    sx, sy = sx * k, sy * k
    w, h = max(round(aw * sx), 2), max(round(ah * sy), 2)
    left, top = round(anchor.x + anchor.width / 2 - w / 2), anchor.y + anchor.height - h
    out = [(replace(anchor, x=left, y=top, width=w, height=h), name)]
    for other, sprite, (_, ox, oy) in members:
        w, h = round(sprite.size[0] * sx), round(sprite.size[1] * sy)
        x, y = left + round((ox - ax) * sx), top + round((oy - ay) * sy)
        if other == name or w < 2 or h < 2 or x >= width or y >= height or x + w <= 0 or y + h <= 0:
            continue
        out.append((replace(anchor, sprite=sprite, x=x, y=y, width=w, height=h), other))
    return out
