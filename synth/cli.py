"""``fuzzyfire synth`` subcommands: flames, cutouts, scenes, method1, method2, audit, gap (registered by ``fuzzyfire.cli``)."""

from __future__ import annotations

import argparse
import json
import os
from pathlib import Path

from curate.core.commands import add_command


def parse_size(text: str) -> tuple[int, int]:
    """``"640x480"`` -> (640, 480)."""
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError as exc:
        raise argparse.ArgumentTypeError(f"size must look like 640x480, got {text!r}") from exc
    return w, h


def cmd_flames(args: argparse.Namespace) -> int:
    from curate.core.progress import progress
    from synth.library import procedural_library
    from synth.preview import write_preview
    from synth.sprites import save_sequence

    texture = _texture(args)
    seqs = procedural_library(
        args.n,
        args.seed,
        args.frames,
        args.keep_every,
        args.rare,
        args.generator,
        texture,
        args.rising_smoke,
        args.exposed,
    )
    for seq in progress(seqs, total=len(seqs), desc="flames"):
        save_sequence(args.out / seq.name, seq)
    preview = write_preview(seqs, args.out / "preview.png")
    print(f"wrote {len(seqs)} sequences ({sum(len(s.sprites) for s in seqs)} sprites) to {args.out}; preview {preview}")
    return 0


def cmd_cutouts(args: argparse.Namespace) -> int:
    import sys

    from curate.core.commands import print_problems, read_from_args
    from curate.core.load import SplitError, pick_split
    from synth.cutouts import cutouts, write_cutouts

    result = read_from_args(args)
    try:
        ds = pick_split(result.dataset, args.split, args.src)
        problems: list = []
        if not 0.0 < args.max_fill <= 1.0:
            raise ValueError(f"--max-fill must be in (0, 1], got {args.max_fill}")
        items = cutouts(ds, args.class_name, args.min_side, args.min_cover, problems, args.mask, args.max_fill)
        n = write_cutouts(items, args.out)
    except (SplitError, ValueError, FileExistsError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if problems:
        print_problems(problems, sys.stderr, limit=20)
    print(
        f"wrote {n} cut-outs of {args.class_name!r} from {len(ds.images)} images to {args.out} (use: --flames {args.out})"
    )
    return 0


def cmd_scenes(args: argparse.Namespace) -> int:
    import cv2
    import numpy as np

    from synth import camera, render, scenes

    args.out.mkdir(parents=True, exist_ok=True)
    w, h = args.size
    with render.Renderer(w, h) as r:
        for i in range(args.n):
            env = scenes.build_environment(i, args.seed)
            scene = scenes.to_pyrender(env, r.pyrender)
            rng = np.random.default_rng([args.seed, 1, i])
            view = camera.find_view(
                env.camera, rng, lambda v, s=scene: render.render_view(r, s, v.pose, v.yfov, True)[1]
            )
            rgb, _ = render.render_view(r, scene, view.pose, view.yfov)
            cv2.imwrite(str(args.out / f"{env.name}.png"), cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))
    print(f"wrote {args.n} environment previews to {args.out}")
    return 0


DEFAULT_SCENES = 48  # procedural rooms when the user brings no backgrounds of their own
DEFAULT_LIBRARY = 12  # procedural flame sequences when --flames is absent
#: The procedural flames' inner streaks when --texture is not given (configs/shared-data.yaml's look).
TEXTURE = 0.5
TEXTURE_HELP = (
    "procedural flames' inner streaks, 0..1: the body's temperature dips by up to this in rising streaks (orange "
    f"tongues inside the yellow) and its edge is softened (default {TEXTURE:g}, the study's look; 0: the earlier flat "
    "clipped body)"
)


RISING_HELP = (
    "procedural flames' smoke only from the flame's middle up, rising from its tips (default: wherever the "
    "simulated soot drifts, also low beside the base, where it can read as a dark stain on the ground)"
)
EXPOSED_HELP = (
    "procedural flames coloured as a camera records a fire: a 900-1600 K black body past the sensor's range, red "
    "edges, orange, yellow and a white core (default: the display palette, a 3000 K body with yellow cores)"
)


def _texture(args: argparse.Namespace) -> float:
    """--texture, or :data:`TEXTURE` for procedural flames when it is not given (0 with --flames: real sprites)."""
    if args.texture is not None:
        return args.texture
    return 0.0 if getattr(args, "flames", None) else TEXTURE


def _scenes(args: argparse.Namespace) -> int:
    """``--scenes``, else none when the user brings environments, photos or kit streets (theirs alone), else 48."""
    if args.scenes is not None:
        return args.scenes
    yours = args.environments or getattr(args, "backgrounds", None) or getattr(args, "frames", None)
    return 0 if yours or args.streets else DEFAULT_SCENES


def _dataset_config(args: argparse.Namespace) -> dict:
    """The config fields Method 1 and Method 2 share, from :func:`_dataset_arguments`, after checking what can be
    checked before the flame library is made: the output folder, the environment files and the photos."""
    from curate.core.writer import check_output_target
    from synth.envfile import find_environment_files
    from synth.kits import find_kits
    from synth.library import FlameLibraryConfig
    from synth.photos import list_photos
    from synth.places import split_places

    check_output_target(args.out, args.overwrite)
    if getattr(args, "backgrounds", None):
        list_photos(args.backgrounds)
    places = split_places(args.environments or (), getattr(args, "backgrounds", None) or ())
    if places.meshes:
        find_environment_files(places.meshes)
    if args.environments and not places.meshes and not places.panoramas:
        raise ValueError(f"no mesh files or 2:1 panoramas in {', '.join(map(str, args.environments))}")
    if args.kits and not args.streets:
        raise ValueError("--kits are the building kits of --streets N, which is not given")
    if args.streets:
        if not args.kits:
            raise ValueError("--streets needs --kits DIR (building kits, e.g. ../shared/data/kits)")
        find_kits(args.kits)

    if args.library is not None and args.flames:
        raise ValueError("--library makes procedural flames, which --flames replaces: give one of them")
    if args.texture and args.flames:
        raise ValueError("--texture shapes procedural flames, which --flames replaces: give one of them")
    if args.rising_smoke and args.flames:
        raise ValueError("--rising-smoke shapes procedural flames, which --flames replaces: give one of them")
    if args.exposed and args.flames:
        raise ValueError("--exposed colours procedural flames, which --flames replaces: give one of them")
    w, h = args.size
    library = DEFAULT_LIBRARY if args.library is None else args.library
    folders = tuple(args.flames or ())
    flames = FlameLibraryConfig(
        sequences=library,
        seed=args.seed,
        folders=folders,
        texture=_texture(args),
        rising_smoke=args.rising_smoke,
        exposed=args.exposed,
        cutout_feather=args.cutout_feather,
        cutout_groups=args.cutout_groups,
        cluster=args.cluster,
    )
    return {
        "n": args.n,
        "seed": args.seed,
        "width": w,
        "height": h,
        "scenes": _scenes(args),
        "environments": tuple(args.environments or ()),
        "streets": args.streets or 0,
        "kits": tuple(args.kits or ()),
        "smoke_class": args.smoke,
        "flames": flames,
    }


def cmd_method1(args: argparse.Namespace) -> int:
    from synth.distractors import DistractorConfig
    from synth.library import build_library
    from synth.method1 import Method1Config, run_method1

    distractors = DistractorConfig(share=args.distractors)
    cfg = Method1Config(box_mode=args.box_mode, distractors=distractors, **_dataset_config(args))
    result = run_method1(cfg, build_library(cfg.flames), args.out, overwrite=args.overwrite, workers=_workers(args))
    print(f"wrote {args.out}: {args.n} images, {args.box_mode} boxes ({', '.join(result.files.values())})")
    return 0


def cmd_method2(args: argparse.Namespace) -> int:
    from synth.library import build_library
    from synth.method2 import Method2Config, run_method2

    if args.photo_share is not None and not (args.backgrounds or args.frames):
        raise ValueError("--photo-share is the share of views on --backgrounds/--frames, which are not given")
    if args.photo_negatives is not None and not args.backgrounds:
        raise ValueError("--photo-negatives is the share of --backgrounds photos left without flames, none are given")
    if args.frame_swap and not args.frames:
        raise ValueError("--frame-swap is the share of --frames images whose fires are swapped, none are given")
    if args.frame_anchored and not args.frames:
        raise ValueError("--frame-anchored places flames beside the fires of --frames images, none are given")
    share = 0.5 if args.photo_share is None else args.photo_share
    photos = {
        "backgrounds": tuple(args.backgrounds or ()),
        "frames": tuple(args.frames or ()),
        "photo_share": share,
        "photo_negatives": args.photo_negatives,
        "frame_swap": args.frame_swap,
        "frame_anchored": args.frame_anchored,
    }
    cfg = Method2Config(**_dataset_config(args), **photos, **_blend_config(args))
    result = run_method2(cfg, build_library(cfg.flames), args.out, overwrite=args.overwrite, workers=_workers(args))
    print(f"wrote {args.out}: {args.n} images ({', '.join(result.files.values())})")
    return 0


def _workers(args: argparse.Namespace) -> int:
    """--workers, 0 = one per core."""
    if args.workers < 0:
        raise ValueError(f"--workers must be >= 0, got {args.workers}")
    return args.workers or os.cpu_count() or 1


def _blend_config(args: argparse.Namespace) -> dict:
    """Method 2's ``blend``, ``distractors``, ``never_darken``, ``opaque_body``, ``auto_exposure``, ``flame_jitter``,
    ``separate_flames`` and ``flame_heights`` from --blend, --harmonise, --match-noise, --decoys, --distractors,
    --never-darken, --opaque-body, --auto-exposure, --flame-jitter, --separate-flames, --flame-heights (the
    defaults: today's blend, none of them but never_darken)."""
    from synth.blend import BlendConfig
    from synth.distractors import DistractorConfig

    modes = tuple(m.strip() for m in args.blend.split(",")) if args.blend else BlendConfig().modes
    blend = BlendConfig(modes=modes, harmonise=args.harmonise, match_noise=args.match_noise, decoys=args.decoys)
    return {
        "blend": blend,
        "distractors": DistractorConfig(share=args.distractors, **_distractor_kinds(args)),
        "never_darken": args.never_darken,
        "opaque_body": args.opaque_body,
        "auto_exposure": args.auto_exposure,
        "flame_jitter": args.flame_jitter,
        "separate_flames": args.separate_flames,
        "flame_heights": args.flame_heights,
    }


def _ious(rep: dict) -> str:
    return f"mean IoU {rep['mean_iou']:.4f}, min IoU {rep['min_iou']:.4f}"


def cmd_audit(args: argparse.Namespace) -> int:
    from synth.audit import audit_dataset

    report = audit_dataset(args.folder)
    if args.json:
        print(json.dumps(report))
    else:
        print(f"{report['images']} images, {report['boxes']} boxes: {_ious(report)}")
        parts = {**report.get("modes", {}), **({"smoke": report["smoke"]} if "smoke" in report else {})}
        for name, rep in parts.items():
            print(f"  {name} boxes: {rep['boxes']}, {_ious(rep)}")
        if "visibility" in report:
            v = report["visibility"]
            seen = (
                ""
                if not v["boxes"]
                else f", contrast ΔE min {v['min_contrast']:.1f}, median {v['median_contrast']:.1f}"
            )
            print(f"  visibility: {v['boxes']} fire boxes{seen}; {v['erased']} flames erased as unseen")
    return 0


def cmd_gap(args: argparse.Namespace) -> int:
    import sys

    import numpy as np

    from curate.cli.dedup import load_model_from_args
    from curate.core.commands import print_problems
    from synth.gap import (
        dataset_boxes,
        dataset_images,
        embed_crops,
        embed_set,
        image_kinds,
        measure_gap,
        split_by_kind,
        synthetic_boxes,
    )

    sides = [(args.synthetic, args.synthetic_split, args.format), (args.real, args.real_split, args.real_format)]
    if args.crops:
        boxes = [dataset_boxes(path, split, fmt, args.class_name) for path, split, fmt in sides]
        if not args.all_boxes:
            boxes[0], left = synthetic_boxes(args.synthetic, boxes[0])
            if left:
                print(
                    f"{args.synthetic}: left out {left} boxes without a flame mask (a labelled frame's own fires, "
                    "real; --all-boxes keeps them)",
                    file=sys.stderr,
                )
            if not boxes[0]:
                print(f"error: {args.synthetic}: no {args.class_name!r} box of a drawn flame", file=sys.stderr)
                return 2
        embedder, _ = load_model_from_args(args)
        synthetic, real = (embed_crops(str(s[0]), b, embedder, args.context) for s, b in zip(sides, boxes))
    else:
        images = [dataset_images(path, split, fmt) for path, split, fmt in sides]
        embedder, cache = load_model_from_args(args)
        synthetic, real = (embed_set(str(s[0]), p, embedder, cache, args.workers) for s, p in zip(sides, images))
    problems = [*synthetic.problems, *real.problems]
    if problems:
        print_problems(problems, sys.stderr, limit=20)
    rng = np.random.default_rng(args.seed)
    unit = "crops" if args.crops else "images"
    report = measure_gap(synthetic, real, embedder.model_id, rng, args.draws, args.size, unit)
    by_kind = {} if args.crops else split_by_kind(synthetic, images[0], image_kinds(args.synthetic))
    kinds = {k: measure_gap(s, real, embedder.model_id, np.random.default_rng(args.seed), args.draws, args.size)
             for k, s in by_kind.items() if len(s.vectors) >= 20}  # fmt: skip
    if args.json:
        print(json.dumps({**report.to_json(), "kinds": {k: r.to_json() for k, r in kinds.items()}}))
    else:
        print("\n".join(report.lines()))
        for kind, r in kinds.items():
            print(f"  {kind:<9} {len(r.synthetic.vectors)} images: {r.gap.synthetic}  ratio {r.gap.ratio.median:.2f}")
    return 0


def cmd_colour(args: argparse.Namespace) -> int:
    import sys

    from curate.core.commands import print_problems
    from curate.core.formats.registry import read_dataset
    from curate.core.load import pick_split
    from synth.flame_colour import flame_colour

    sides = {"synthetic": (args.synthetic, args.synthetic_split), "real": (args.real, args.real_split)}
    problems: list = []
    measured = {}
    for name, (path, split) in sides.items():
        result = read_dataset(path)
        problems += result.problems
        measured[name] = flame_colour(pick_split(result.dataset, split, path), args.class_name, problems)
    if problems:
        print_problems(problems, sys.stderr, limit=20)
    if args.json:
        print(json.dumps({name: c.to_dict() for name, c in measured.items()}))
        return 0
    print(f"flame colour of the {args.class_name!r} boxes (their GrabCut flame pixels; synth/flame_colour.py)")
    print(f"{'':<10} {'boxes':>6} {'near-white':>10} {'saturation':>10} {'hue':>6} {'red':>6}")
    for name, c in measured.items():
        path, split = sides[name]
        where = f"{path}" + (f" ({split})" if split else "")
        line = f"{c.boxes:>6} {100 * c.white:>9.1f}% {c.saturation:>10.2f} {c.hue:>5.0f}° {100 * c.red:>5.1f}%"
        print(f"{name:<10} {line}  {where}")
    return 0


def _add_pair(p: argparse.ArgumentParser, synthetic_help: str, real_help: str) -> None:
    """The SYNTHETIC and REAL positionals of a command comparing two sets, and a split option for each."""
    p.add_argument("synthetic", type=Path, help=synthetic_help)
    p.add_argument("real", type=Path, help=real_help)
    p.add_argument("--synthetic-split", help="only this split of SYNTHETIC (default: every image)")
    p.add_argument("--real-split", help="only this split of REAL (default: every image)")


def _register_colour(sub: argparse._SubParsersAction) -> None:
    p = add_command(
        sub,
        "colour",
        help="flame colour: near-white cores, saturation, hue and red edges of a set's flames against a real set's",
        description="Measure the flames of a labelled synthetic set against a real one in four figures you can\n"
        "check by eye: the share of near-white (over-exposed) flame pixels, their median saturation, the median hue of\n"
        "the colourful ones (0 red, 30 orange, 60 yellow) and the share of those that are red. Flame pixels: the\n"
        "GrabCut cut-out mask of every --class box (the rule of synth cutouts), on both sides.\n\n"
        "example:\n  fuzzyfire synth colour out/m2 ../shared/data/fire-cctv-416 --real-split train\n"
        "  fuzzyfire synth colour out/m2-exposed out/curated --real-split train --json",
    )
    _add_pair(p, "synthetic dataset, any labelled format", "real dataset, any labelled format")
    p.add_argument("--class", dest="class_name", default="fire", help="the flames' class (default fire)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=cmd_colour)


def _register_flames(sub: argparse._SubParsersAction) -> None:
    p = add_command(
        sub,
        "flames",
        help="simulate procedural flame sprite sequences",
        description="Simulate flame sequences (stable fluids or noise), keep every K-th frame. Each sequence is a\n"
        "folder of NNNN_emission.png (the flame's light on black), NNNN_mask.png and, for frames with smoke,\n"
        "NNNN_smoke.png (RGBA); preview.png shows every sequence composited over a dark and a light background.\n\n"
        "example:\n  fuzzyfire synth flames --out out/flames --n 12 --seed 0 --frames 1024 --keep-every 12",
    )
    p.add_argument("--out", required=True, type=Path, help="folder for the sequence folders")
    p.add_argument("--n", type=int, default=12, help="number of sequences")
    p.add_argument("--seed", type=int, default=0, help="random seed")
    p.add_argument("--generator", default="fluid", choices=("fluid", "noise"), help="flame simulation")
    p.add_argument("--frames", type=int, default=1024, help="simulation steps per sequence")
    p.add_argument("--keep-every", type=int, default=12, help="keep one frame every K steps")
    rare = (
        "probability that a sequence is a chemical-colour (rare) flame (drawn per sequence: the count varies by seed)"
    )
    p.add_argument("--rare", type=float, default=0.05, help=rare)
    p.add_argument("--texture", type=float, help=TEXTURE_HELP)
    p.add_argument("--rising-smoke", action="store_true", help=RISING_HELP)
    p.add_argument("--exposed", action="store_true", help=EXPOSED_HELP)
    p.set_defaults(func=cmd_flames)


def _register_cutouts(sub: argparse._SubParsersAction) -> None:
    from curate.core.commands import add_reader_args

    p = add_command(
        sub,
        "cutouts",
        help="cut real flames out of a labelled dataset (RGBA sprites for --flames)",
        description="Cut the flame pixels of each box of a labelled real dataset into RGBA PNG sprites (--mask:\n"
        "grabcut refines the fire-coloured pixels with the image's own colours; colour keeps them as they are),\n"
        "25 per sequence folder, with cutouts.json naming each one's source image and box. Method 1 and 2 take\n"
        "the folder as a flame library (--flames, or flames.folders in a config): real flames in rendered\n"
        "scenes, which separates the flames' share of the realism gap from the scenes' share.\n\n"
        "example:\n  fuzzyfire synth cutouts ../shared/data/fire-cctv-416 --split train --out out/cutouts\n"
        "  fuzzyfire synth method2 --environments ../shared/data/scenes --flames out/cutouts --n 200 --out out/m2-real",
    )
    p.add_argument("src", help="labelled dataset folder (any layout fuzzyfire reads)")
    p.add_argument("--out", required=True, type=Path, help="new folder for the sequence folders")
    p.add_argument("--split", help="only this split (default: every image)")
    p.add_argument("--class", dest="class_name", default="fire", help="class to cut out (default fire)")
    p.add_argument("--min-side", type=int, default=16, help="skip boxes smaller than this, pixels (default 16)")
    p.add_argument(
        "--min-cover", type=float, default=0.08, help="skip boxes less fire-coloured than this share (default 0.08)"
    )
    p.add_argument("--mask", default="grabcut", choices=("colour", "grabcut"), help="flame mask rule (default grabcut)")
    p.add_argument(
        "--max-fill",
        type=float,
        default=1.0,
        help="skip cut-outs whose flame mask fills more than this share of the box: fire-lit rectangles, not "
        "flame shapes (default 1: keep all; 0.85 drops ~14 %% of fire-cctv-416's)",
    )
    add_reader_args(p, source=False)
    p.set_defaults(func=cmd_cutouts)


def _register_scenes(sub: argparse._SubParsersAction) -> None:
    p = add_command(
        sub,
        "scenes",
        help="render one preview per procedural environment",
        description="Render a preview PNG of each of the first N environments.\n\n"
        "example:\n  fuzzyfire synth scenes --out out/scenes --n 48 --size 320x240",
    )
    p.add_argument("--out", required=True, type=Path, help="folder for the preview PNGs")
    p.add_argument("--n", type=int, default=48, help="procedural environments to preview")
    p.add_argument("--seed", type=int, default=0, help="random seed")
    p.add_argument("--size", type=parse_size, default="320x240", help="preview size WxH in pixels")
    p.set_defaults(func=cmd_scenes)


def _dataset_arguments(p: argparse.ArgumentParser, photos: bool = False) -> None:
    """Method 1 and Method 2's options (``photos``: Method 2's --backgrounds exists)."""
    yours = "--environments or --backgrounds are" if photos else "--environments are"
    p.add_argument("--out", required=True, type=Path, help="output dataset folder")
    p.add_argument("--n", type=int, default=100, help="images to generate")
    p.add_argument("--seed", type=int, default=0, help="random seed (the same seed gives the same images)")
    p.add_argument("--size", type=parse_size, default="640x480", help="image size WxH in pixels")
    p.add_argument(
        "--scenes",
        type=int,
        help=f"procedural rooms (default: {DEFAULT_SCENES}, or 0 when {yours} given: then only yours are used; "
        "pass --scenes N to add N procedural rooms to them)",
    )
    p.add_argument(
        "--environments",
        type=Path,
        nargs="+",
        metavar="PATH",
        help="places: 3D environments (glTF/GLB/OBJ/PLY files, folders of them, or sidecar YAMLs: synth/envfile.py) "
        "and, for Method 2, 360-degree panoramas (2:1 JPEG/PNG/HDR images or folders of them: synth/panorama.py)",
    )
    p.add_argument(
        "--streets",
        type=int,
        metavar="N",
        help="N procedural streets laid out from the building kits of --kits (synth/streets.py; default 0)",
    )
    p.add_argument(
        "--kits",
        type=Path,
        nargs="+",
        metavar="DIR",
        help="building kit folders, or a folder of them (Kenney City Kit Suburban, Retro Urban: synth/kits.py)",
    )
    p.add_argument("--flames", type=Path, nargs="*", help="sequence folders (synth flames output, or RGBA PNGs)")
    p.add_argument(
        "--cluster",
        type=int,
        default=1,
        metavar="N",
        help="each flame a fire of 1..N flames side by side on one base, boxed whole as annotators box a burning "
        "region (synth/clusters.py; default 1: single flames)",
    )
    p.add_argument(
        "--cutout-feather",
        type=float,
        default=0.0,
        metavar="F",
        help="with --flames folders written by synth cutouts: fade each cut-out towards the sides of its box that its "
        "flame runs into, over F (0..0.5) of the box (no hard rectangle edges; synth/feather.py; default 0)",
    )
    p.add_argument(
        "--cutout-groups",
        action="store_true",
        help="Method 2, with --flames folders written by synth cutouts: a cut-out comes with the other cut-outs of its "
        "image, where they sat and as large, each with its own box (a burning building boxed window by window; "
        "synth/groups.py)",
    )
    p.add_argument(
        "--library",
        type=int,
        help=f"procedural flame sequences to make instead of --flames (default {DEFAULT_LIBRARY})",
    )
    p.add_argument("--texture", type=float, help=TEXTURE_HELP)
    p.add_argument("--rising-smoke", action="store_true", help=RISING_HELP)
    p.add_argument("--exposed", action="store_true", help=EXPOSED_HELP)
    p.add_argument("--overwrite", action="store_true", help="replace a fuzzyfire dataset already at --out")
    p.add_argument("--smoke", action="store_true", help="also annotate smoke (class 'smoke', alpha >= 0.25)")
    p.add_argument(
        "--workers",
        type=int,
        default=0,
        help="image processes (default 0 = one per core; any number writes the same bytes)",
    )


def _register_method1(sub: argparse._SubParsersAction) -> None:
    p = add_command(
        sub,
        "method1",
        help="Method 1: flame planes in the 3D scenes (paper boxes vs visible boxes)",
        description="Place flame image planes in the rendered environments (camera rules as in the paper)\n"
        "and annotate them with the visible box (segmentation pass + warped flame mask, occlusion\n"
        "handled) or the paper's box (projected plane corners, clipped). Both box sets are kept in\n"
        "masks/box_modes.json; `synth audit` reports both. Resumes an interrupted run.\n\n"
        "example:\n  fuzzyfire synth method1 --n 1000 --seed 0 --out out/m1 --size 640x480 --scenes 48\n"
        "  fuzzyfire synth method1 --n 200 --out out/m1-paper --box-mode paper\n"
        "  fuzzyfire synth method1 --n 200 --out out/m1-streets --streets 8 --kits ../shared/data/kits\n"
        "  fuzzyfire synth method1 --n 200 --out out/m1-hard --environments configs/scenes --distractors 0.5\n"
        "  fuzzyfire synth audit out/m1 --json",
    )
    _dataset_arguments(p)
    p.add_argument("--box-mode", default="visible", choices=("visible", "paper"), help="annotation written")
    _distractor_argument(p)
    p.set_defaults(func=cmd_method1)


def _register_method2(sub: argparse._SubParsersAction) -> None:
    p = add_command(
        sub,
        "method2",
        help="Method 2: composite flames on rendered views (exact boxes)",
        description="Render environment views once and composite flame sprites on them; boxes come\n"
        "from each flame's final visible mask. Backgrounds: procedural scenes, 3D files (--environments)\n"
        "and/or your fire-free photos (--backgrounds). Resumes an interrupted run.\n\n"
        "example:\n  fuzzyfire synth method2 --n 1000 --seed 0 --out out/m2 --size 640x480 --scenes 48\n"
        "  fuzzyfire synth method2 --n 200 --out out/m2-rooms --environments configs/scenes\n"
        "  fuzzyfire synth method2 --n 200 --out out/m2-photos --backgrounds my/negatives\n"
        "  fuzzyfire synth method2 --n 200 --out out/m2-negatives --environments ../shared/data/panoramas "
        "--backgrounds my/negatives --photo-share 0.3 --photo-negatives 1  # your photos as they are, no flame\n"
        "  fuzzyfire synth method2 --n 200 --out out/m2-frames --frames my/cctv-labelled  # keeps their boxes\n"
        "  fuzzyfire synth method2 --n 200 --out out/m2-panoramas --environments ../shared/data/panoramas\n"
        "  fuzzyfire synth method2 --n 200 --out out/m2-mixed --environments configs/scenes --scenes 24\n"
        "  fuzzyfire synth method2 --n 200 --out out/m2-streets --streets 8 --kits ../shared/data/kits\n"
        "  fuzzyfire synth method2 --n 200 --out out/m2-hard --environments ../shared/data/panoramas "
        "--distractors 0.5 --blend screen,add,alpha,blur,poisson --harmonise --match-noise --decoys 0.3\n"
        "  fuzzyfire synth method2 --n 200 --out out/m2-own-negatives --backgrounds my/negatives "
        "--distractors 0.5 --distractor-kinds photo,lights  # your photos' lamps and red sofas pasted, unboxed\n"
        "  fuzzyfire synth audit out/m2 --json",
    )
    _dataset_arguments(p, photos=True)
    p.add_argument("--backgrounds", type=Path, nargs="+", metavar="PATH", help="fire-free photos (files or folders)")
    p.add_argument(
        "--frames",
        type=Path,
        nargs="+",
        metavar="DATASET",
        help="labelled datasets (any format, e.g. your cameras' frames with their fire boxes): composited on like "
        "photos; each keeps its own fire boxes as labels and no flame is placed over them",
    )
    p.add_argument(
        "--frame-swap",
        type=float,
        default=0.0,
        metavar="SHARE",
        help="share (0..1) of the --frames images whose own fires are erased and other flames drawn in their boxes "
        "(synth/swap.py): your fires' places, light and smoke with new flames (default 0: frames keep their fires)",
    )
    p.add_argument(
        "--frame-anchored",
        action="store_true",
        help="on a --frames image with fires, each new flame stands beside one of them (its foot near that fire's "
        "foot, 0.6-1.5x its height) instead of on the image's estimated ground",
    )
    p.add_argument(
        "--photo-share",
        type=float,
        help="share of views on a --backgrounds photo or --frames image when 3D scenes are also used (default 0.5)",
    )
    p.add_argument(
        "--photo-negatives",
        type=float,
        metavar="SHARE",
        help="share (0..1) of the images on a --backgrounds photo left without flames: your fire-free photos as "
        "hard negatives, as they are (default: as every image, 10 %%)",
    )
    _blend_arguments(p)
    p.set_defaults(func=cmd_method2)


def _distractor_argument(p: argparse.ArgumentParser) -> None:
    """--distractors SHARE of Method 1 and 2 (synth/distractors.py)."""
    p.add_argument(
        "--distractors",
        type=float,
        default=0.0,
        metavar="SHARE",
        help="share of images (0..1) carrying 1-2 fire-like things that are not fire and get no box: lamps, a low "
        "sun, traffic cones, red cloth, orange jackets, car tail lights, glare (default 0)",
    )


def _distractor_kinds(args: argparse.Namespace) -> dict:
    """``kinds`` of Method 2's distractors from --distractor-kinds (none: the config's default kinds)."""
    return {"kinds": tuple(k.strip() for k in args.distractor_kinds.split(","))} if args.distractor_kinds else {}


def _blend_arguments(p: argparse.ArgumentParser) -> None:
    """Method 2's distractors and blends (synth/distractors.py, synth/blend.py)."""
    _distractor_argument(p)
    p.add_argument(
        "--distractor-kinds",
        metavar="KINDS",
        help="comma-separated distractor kinds: lamp, sun, cone, cloth, clothing, taillights, glare (drawn; the "
        "default is all of them), photo (fire-coloured regions cut from your --backgrounds photos: orange lamp "
        "shades, lit windows, red sofas) and lights (their light sources with their glow: white-hot lamps, street "
        "lights, windows at night; synth/photo_regions.py)",
    )
    p.add_argument(
        "--blend",
        metavar="MODES",
        help="comma-separated blend modes drawn per flame: screen, add (light), alpha (feathered paste), blur "
        "(blurred edge), poisson (seamless clone) (default screen,add)",
    )
    p.add_argument("--harmonise", action="store_true", help="tint each flame towards the local background light")
    p.add_argument(
        "--never-darken",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="a flame's dim edge reddens a bright background instead of outlining it darker (light blends; default "
        "on, the study's look: --no-never-darken for the earlier compositing)",
    )
    p.add_argument(
        "--opaque-body",
        action="store_true",
        help="with --never-darken: a flame's bright body still hides a bright background (no pale film over a "
        "sunlit wall); only its dim edge never darkens",
    )
    p.add_argument(
        "--auto-exposure",
        action="store_true",
        help="the camera meters each frame with its flames in view: bright flames lower the exposure of the scene "
        "around them, as in real fire footage (no washed-out film over bright walls; synth/metering.py)",
    )
    p.add_argument(
        "--flame-jitter",
        action="store_true",
        help="each flame mirrored or not, 0.75-1.33x as wide, its hue and saturation turned a little (synth/jitter.py)",
    )
    p.add_argument(
        "--separate-flames",
        action="store_true",
        help="on a photo or panorama no two flames overlap (each keeps clear of the ones placed before it)",
    )
    p.add_argument(
        "--flame-heights",
        choices=("uniform", "log"),
        default="uniform",
        help="flame heights in metres drawn uniform (default) or log-uniform (more small, far flames)",
    )
    p.add_argument("--match-noise", action="store_true", help="blur and grain each flame like the background around it")
    p.add_argument(
        "--decoys",
        type=float,
        default=0.0,
        metavar="SHARE",
        help="share of images (0..1) with decoy pastes: background patches pasted with a flame's shape and blend, no box",
    )


def _register_audit(sub: argparse._SubParsersAction) -> None:
    p = add_command(
        sub,
        "audit",
        help="IoU of written boxes vs pixel-truth mask boxes, and the boxed flames' visibility",
        description="Compare a synthetic dataset's boxes with the boxes of its kept flame masks; for Method 2,\n"
        "also the boxed flames' contrast against the flame-free background (ΔE*ab, min and median) and how\n"
        "many flames were erased because nobody could see them (synth/visibility.py).\n\n"
        "example:\n  fuzzyfire synth audit out/m2 --json",
    )
    p.add_argument("folder", type=Path, help="a dataset written by synth method1 or method2")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=cmd_audit)


def _register_gap(sub: argparse._SubParsersAction) -> None:
    from curate.cli.dedup import add_model_args

    p = add_command(
        sub,
        "gap",
        help="realism gap: Fréchet distance of CNN embeddings, synthetic vs real, with the real-vs-real floor",
        description="How far a synthetic set is from a real one: the Fréchet distance between the Gaussians of\n"
        "their CNN embeddings (ImageNet EfficientNet-Lite0 unless --model), at equal sizes against half of the\n"
        "real set, next to the distance of the real set's other half (the floor). Median and 2.5-97.5 % range\n"
        "over --draws random splits; embeddings are cached like curation's. --crops measures the flame gap\n"
        "instead: the same distance over the boxes of --class cut out with --context around them (not cached).\n\n"
        "example:\n  fuzzyfire synth gap out/m2 ../shared/data/fire-cctv-416 --real-split train\n"
        "  fuzzyfire synth gap out/m2 ../shared/data/fire-cctv-416 --real-split train --crops\n"
        "  fuzzyfire synth gap renders/ photos/ --format images --real-format images --json",
    )
    _add_pair(
        p,
        "synthetic dataset (or image folder with --format images)",
        "real dataset (or image folder with --real-format images)",
    )
    formats = ["auto", "coco", "yolo", "voc", "dfire", "images"]
    p.add_argument("--format", default="auto", choices=formats, help="layout of SYNTHETIC (default auto)")
    p.add_argument("--real-format", default="auto", choices=formats, help="layout of REAL (default auto)")
    p.add_argument("--draws", type=int, default=200, help="random equal-size draws (default 200)")
    p.add_argument("--size", type=int, help="images (crops) per side (default min(synthetic, real / 2))")
    p.add_argument("--crops", action="store_true", help="the flame gap: compare box crops, not whole images")
    p.add_argument("--class", dest="class_name", default="fire", help="with --crops: the boxes' class (default fire)")
    p.add_argument(
        "--all-boxes",
        action="store_true",
        help="with --crops: also the boxes a pool has no flame mask for (the own fires of the labelled frames it "
        "composited on; left out by default: they are real flames)",
    )
    p.add_argument(
        "--context", type=float, default=0.1, help="with --crops: context around a box, fraction of its size (0.1)"
    )
    p.add_argument("--seed", type=int, default=0, help="seed of the draws (default 0)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    add_model_args(p)
    p.set_defaults(func=cmd_gap)


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``fuzzyfire synth ...`` to the ``fuzzyfire`` parser."""
    synth = add_command(
        sub,
        "synth",
        help="procedural flames, environments and synthetic datasets",
        description="Synthetic data: flames, cut-outs, scenes, Method 1, Method 2, audit, realism gap, flame colour.\n\n"
        "example:\n  fuzzyfire synth method2 --n 200 --out out/m2 --size 320x240",
    )
    inner = synth.add_subparsers(dest="synth_command", metavar="SUBCOMMAND")
    for add in (
        _register_flames,
        _register_cutouts,
        _register_scenes,
        _register_method1,
        _register_method2,
        _register_audit,
        _register_gap,
        _register_colour,
    ):
        add(inner)
