"""``fuzzyfire synth`` subcommands: flames, cutouts, scenes, method1, method2, audit, gap (registered by ``fuzzyfire.cli``)."""

from __future__ import annotations

import argparse
import json
import os
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from curate.cli.dedup import add_cache_args, embedding_run_aliases, model_aliases
from ground.cli.commands import add_command
from ground.cli.options import Alias, add_settings, one_of
from ground.run.cluster import EXECUTOR_CHOICES, open_cluster

if TYPE_CHECKING:
    from ground.data.writer import WriteResult
    from synth.method_config import MethodConfig


def parse_size(text: str) -> tuple[int, int]:
    """``"640x480"`` -> (640, 480)."""
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError as exc:
        raise argparse.ArgumentTypeError(f"size must look like 640x480, got {text!r}") from exc
    return w, h


def cmd_flames(args: argparse.Namespace) -> int:
    from ground.cli.options import command_config
    from ground.run.progress import progress
    from synth.flames.library import FlameLibraryConfig, build_library
    from synth.flames.preview import write_preview
    from synth.flames.sprites import save_sequence

    cfg = command_config(args, FlameLibraryConfig, FLAME_ALIASES)
    if cfg is None:
        return 0
    if cfg.folders or cfg.source != "simulated":
        raise ValueError("synth flames simulates flames: folders and source cutouts have nothing to simulate")
    seqs = build_library(cfg)
    for seq in progress(seqs, total=len(seqs), desc="flames"):
        save_sequence(args.out / seq.name, seq)
    preview = write_preview(seqs, args.out / "preview.png")
    print(f"wrote {len(seqs)} sequences ({sum(len(s.sprites) for s in seqs)} sprites) to {args.out}; preview {preview}")
    return 0


def cmd_cutouts(args: argparse.Namespace) -> int:
    import sys

    from ground.cli.commands import print_problems, read_from_args
    from ground.cli.options import command_config
    from ground.data.classes import canonical_class
    from ground.data.load import SplitError, pick_split
    from synth.flames.cutouts import CutoutConfig, cutouts, write_cutouts

    cfg = command_config(args, CutoutConfig, CUTOUT_ALIASES, {"SRC": args.src, "--out": args.out})
    if cfg is None:
        return 0
    result = read_from_args(args)
    try:
        ds = pick_split(result.dataset, args.split, args.src)
        problems: list = []
        n = write_cutouts(cutouts(ds, cfg, problems), args.out)
    except (SplitError, ValueError, FileExistsError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if problems:
        print_problems(problems, sys.stderr, limit=20)
    use = f"--flames {args.out}"
    if canonical_class(cfg.class_name) == "smoke":
        use += " beside a flame folder, in synth method2 with --set smoke.source=cutouts --set smoke.alone=0.5"
    print(f"wrote {n} cut-outs of {cfg.class_name!r} from {len(ds.images)} images to {args.out} (use: {use})")
    return 0


def cmd_scenes(args: argparse.Namespace) -> int:
    import cv2
    import numpy as np

    from ground.cli.options import command_config
    from synth.places import camera, render, scenes

    cfg = command_config(args, scenes.ScenesConfig, SCENES_ALIASES, {"--out": args.out})
    if cfg is None:
        return 0
    args.out.mkdir(parents=True, exist_ok=True)
    with render.Renderer(cfg.width, cfg.height) as r:
        for i in range(cfg.n):
            env = scenes.build_environment(i, cfg.seed)
            scene = scenes.to_pyrender(env, r.pyrender)
            rng = np.random.default_rng([cfg.seed, 1, i])
            view = camera.find_view(
                env.camera, rng, lambda v, s=scene: render.render_view(r, s, v.pose, v.yfov, True)[1]
            )
            rgb, _ = render.render_view(r, scene, view.pose, view.yfov)
            cv2.imwrite(str(args.out / f"{env.name}.png"), cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))
    print(f"wrote {cfg.n} environment previews to {args.out}")
    return 0


def _size_keys(size: tuple[int, int]) -> dict[str, int]:
    return {"width": size[0], "height": size[1]}


#: Flags of ``synth cutouts`` (keys of synth.flames.cutouts.CutoutConfig).
CUTOUT_ALIASES: tuple[Alias, ...] = (
    Alias("--class", ("class_name",), "class to cut out", {}),
    Alias("--min-side", ("min_side",), "skip boxes smaller than this on either side, pixels", {"type": int}),
    Alias("--min-cover", ("min_cover",), "skip boxes less fire-coloured than this share", {"type": float}),
    Alias("--mask", ("mask",), "flame mask rule", one_of(("colour", "grabcut"))),
)  # fmt: skip

#: Flags of ``synth colour`` (keys of synth.flames.cutouts.CutoutConfig: its flame pixels are cut-outs').
COLOUR_ALIASES: tuple[Alias, ...] = (Alias("--class", ("class_name",), "the flames' class", {}),)

#: Flags of ``synth scenes`` (keys of synth.places.scenes.ScenesConfig).
SCENES_ALIASES: tuple[Alias, ...] = (
    Alias("--n", ("n",), "procedural environments to preview", {"type": int}),
    Alias("--seed", ("seed",), "the environments' seed", {"type": int}),
    Alias("--size", ("width", "height"), "preview size WxH, pixels", {"type": parse_size, "metavar": "WxH"},
          _size_keys),
)  # fmt: skip

#: Flags of ``synth gap`` (keys of synth.gap.GapConfig).
GAP_ALIASES: tuple[Alias, ...] = (
    Alias("--format", ("format",), "layout of SYNTHETIC", one_of(("auto", "coco", "yolo", "voc", "dfire", "images"))),
    Alias("--real-format", ("real_format",), "layout of REAL",
          one_of(("auto", "coco", "yolo", "voc", "dfire", "images"))),
    Alias("--draws", ("draws",), "random equal-size draws", {"type": int}),
    Alias("--size", ("size",), "images (crops) per side (null: min(synthetic, real / 2))", {"type": int}),
    Alias("--seed", ("seed",), "seed of the draws", {"type": int}),
    Alias("--crops", ("crops",), "the flame gap: compare box crops, not whole images", {"action": "store_true"}),
    Alias("--class", ("class_name",), "with --crops: the boxes' class", {}),
    Alias("--all-boxes", ("all_boxes",), "with --crops: also the boxes a pool has no flame mask for (the own fires "
          "of the labelled frames it composited on; left out by default: they are real flames)",
          {"action": "store_true"}),
    Alias("--context", ("context",), "with --crops: context around a box, fraction of its size", {"type": float}),
    *model_aliases(),
    *embedding_run_aliases(),
)  # fmt: skip


#: Flags of ``synth flames`` (keys of synth.flames.library.FlameLibraryConfig).
FLAME_ALIASES: tuple[Alias, ...] = (
    Alias("--n", ("sequences",), "procedural flame sequences to simulate", {"type": int, "metavar": "N"}),
    Alias("--seed", ("seed",), "library seed", {"type": int}),
    Alias("--frames", ("frames",), "simulation steps per sequence (the paper: 1024)", {"type": int}),
    Alias("--keep-every", ("keep_every",), "keep one frame every K steps", {"type": int, "metavar": "K"}),
    Alias("--generator", ("generator",), "flame simulation", {"choices": ("fluid", "noise")}),
    Alias("--rare", ("rare",), "probability per sequence of a chemical-colour flame", {"type": float}),
    Alias("--texture", ("texture",), "inner streaks and soft edge, [0, 1); 0 = flat body", {"type": float}),
    Alias("--exposed", ("exposed",), "coloured as a camera records fire: white cores, red edges", {"action": "store_true"}),
)  # fmt: skip

#: Flags Method 1 and Method 2 share (keys of their configs).
DATASET_ALIASES: tuple[Alias, ...] = (
    Alias("--n", ("n",), "images to write", {"type": int}),
    Alias("--seed", ("seed",), "random seed: the same seed gives the same bytes", {"type": int}),
    Alias("--size", ("width", "height"), "image size WxH, pixels", {"type": parse_size, "metavar": "WxH"}, _size_keys),
    Alias("--scenes", ("scenes",), "procedural rooms (null: 48 unless you bring places)", {"type": int}),
    Alias("--environments", ("environments",), "3D files / folders / sidecar YAMLs (and, Method 2, 2:1 panoramas)",
          {"type": Path, "nargs": "+", "metavar": "PATH"}),
    Alias("--flames", ("flames.folders",), "flame sequence folders (synth flames or synth cutouts output)",
          {"type": Path, "nargs": "+", "metavar": "DIR"}),
    Alias("--images-per-view", ("images_per_view",), "images made from each rendered view", {"type": int}),
    Alias("--smoke", ("smoke_class",), "also annotate smoke (class 'smoke')", {"action": "store_true"}),
)  # fmt: skip

METHOD1_ALIASES: tuple[Alias, ...] = (
    *DATASET_ALIASES,
    Alias("--box-mode", ("box_mode",), "annotation written: visible boxes or the paper's projected corners",
          {"choices": ("visible", "paper")}),
)  # fmt: skip

METHOD2_ALIASES: tuple[Alias, ...] = (
    *DATASET_ALIASES,
    Alias("--backgrounds", ("backgrounds",), "your fire-free photos (files or folders), composited on",
          {"type": Path, "nargs": "+", "metavar": "PATH"}),
    Alias("--labelled-frames", ("labelled_frames",), "labelled datasets composited on like photos, each image "
          "keeping its fire boxes", {"type": Path, "nargs": "+", "metavar": "DATASET"}),
    Alias("--photo-share", ("photo_share",), "share of views on photos or labelled frames beside 3D scenes",
          {"type": float}),
    Alias("--photo-negatives", ("photo_negatives",), "share of photo images left without flames (hard negatives)",
          {"type": float, "metavar": "SHARE"}),
    Alias("--auto-exposure", ("auto_exposure",), "bright flames lower the exposure of the scene around them",
          {"action": "store_true"}),
    Alias("--exposed", ("flames.exposed",), "procedural flames coloured as a camera records fire",
          {"action": "store_true"}),
)  # fmt: skip


def _built(args: argparse.Namespace, schema: type, aliases: Sequence[Alias]):
    """The config of a dataset command, or None after ``--print-config`` printed it; the output folder and the
    places are checked before the flame library is made."""
    from ground.cli.options import command_config
    from ground.data.writer import check_output_target
    from synth.places.envfile import find_environment_files

    cfg = command_config(args, schema, aliases)
    if cfg is None:
        return None
    if args.out is None:
        raise ValueError("--out is required (the output dataset folder)")
    check_output_target(args.out, args.overwrite)
    places = cfg.places().split()
    if places.meshes:
        find_environment_files(places.meshes)
    if cfg.environments and not places.meshes and not places.panoramas:
        raise ValueError(f"no mesh files or 2:1 panoramas in {', '.join(map(str, cfg.environments))}")
    return cfg


def cmd_method1(args: argparse.Namespace) -> int:
    from synth.method1 import Method1Config

    cfg = _built(args, Method1Config, METHOD1_ALIASES)
    if cfg is None:
        return 0
    result = _generate(args, cfg)
    print(f"wrote {args.out}: {cfg.n} images, {cfg.box_mode} boxes ({', '.join(result.files.values())})")
    return 0


def cmd_method2(args: argparse.Namespace) -> int:
    from synth.method2 import Method2Config

    cfg = _built(args, Method2Config, METHOD2_ALIASES)
    if cfg is None:
        return 0
    result = _generate(args, cfg)
    print(f"wrote {args.out}: {cfg.n} images ({', '.join(result.files.values())})")
    return 0


def _generate(args: argparse.Namespace, cfg: MethodConfig) -> WriteResult:
    """``cfg``'s dataset at ``--out`` with the flame library of ``cfg.flames``, in ``--workers`` processes or on
    the Ray cluster of ``--executor ray``."""
    from synth.generate import generate, run_library

    library = run_library(cfg)
    cluster = open_cluster(args.executor or "local", args.address)
    try:
        return generate(cfg, library, args.out, overwrite=args.overwrite, workers=_workers(args), cluster=cluster)
    finally:
        if cluster is not None:
            cluster.close()


def _workers(args: argparse.Namespace) -> int:
    """--workers; not given (or 0): one per core."""
    if args.workers is not None and args.workers < 0:
        raise ValueError(f"--workers must be >= 0, got {args.workers}")
    return args.workers or os.cpu_count() or 1


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

    from curate.cli.dedup import load_model
    from ground.cli.commands import print_problems
    from ground.cli.options import command_config
    from synth.gap import (
        GapConfig,
        dataset_boxes,
        dataset_images,
        embed_crops,
        embed_set,
        image_kinds,
        measure_gap,
        split_by_kind,
        synthetic_boxes,
    )

    cfg = command_config(args, GapConfig, GAP_ALIASES, {"SYNTHETIC": args.synthetic, "REAL": args.real})
    if cfg is None:
        return 0
    sides = [(args.synthetic, args.synthetic_split, cfg.format), (args.real, args.real_split, cfg.real_format)]
    if cfg.crops:
        boxes = [dataset_boxes(path, split, fmt, cfg.class_name) for path, split, fmt in sides]
        if not cfg.all_boxes:
            boxes[0], left = synthetic_boxes(args.synthetic, boxes[0])
            if left:
                print(
                    f"{args.synthetic}: left out {left} boxes without a flame mask (a labelled frame's own fires, "
                    "real; --all-boxes keeps them)",
                    file=sys.stderr,
                )
            if not boxes[0]:
                print(f"error: {args.synthetic}: no {cfg.class_name!r} box of a drawn flame", file=sys.stderr)
                return 2
        embedder, _ = load_model(cfg.model, args)
        synthetic, real = (embed_crops(str(s[0]), b, embedder, cfg.context) for s, b in zip(sides, boxes))
    else:
        images = [dataset_images(path, split, fmt) for path, split, fmt in sides]
        embedder, cache = load_model(cfg.model, args)
        synthetic, real = (embed_set(str(s[0]), p, embedder, cache, cfg.model.workers) for s, p in zip(sides, images))
    problems = [*synthetic.problems, *real.problems]
    if problems:
        print_problems(problems, sys.stderr, limit=20)
    rng = np.random.default_rng(cfg.seed)
    unit = "crops" if cfg.crops else "images"
    report = measure_gap(synthetic, real, embedder.model_id, rng, cfg.draws, cfg.size, unit)
    by_kind = {} if cfg.crops else split_by_kind(synthetic, images[0], image_kinds(args.synthetic))
    kinds = {k: measure_gap(s, real, embedder.model_id, np.random.default_rng(cfg.seed), cfg.draws, cfg.size)
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

    from ground.cli.commands import print_problems
    from ground.cli.options import command_config
    from ground.data.formats.registry import read_dataset
    from ground.data.load import pick_split
    from synth.flames.cutouts import CutoutConfig
    from synth.flames.measure import flame_colour

    cfg = command_config(args, CutoutConfig, COLOUR_ALIASES, {"SYNTHETIC": args.synthetic, "REAL": args.real})
    if cfg is None:
        return 0
    sides = {"synthetic": (args.synthetic, args.synthetic_split), "real": (args.real, args.real_split)}
    problems: list = []
    measured = {}
    for name, (path, split) in sides.items():
        result = read_dataset(path)
        problems += result.problems
        measured[name] = flame_colour(pick_split(result.dataset, split, path), cfg, problems)
    if problems:
        print_problems(problems, sys.stderr, limit=20)
    if args.json:
        print(json.dumps({name: c.to_dict() for name, c in measured.items()}))
        return 0
    rule = {"grabcut": "GrabCut", "colour": "colour-rule"}[cfg.mask]
    print(f"flame colour of the {cfg.class_name!r} boxes (their {rule} flame pixels; synth/flames/measure.py)")
    print(f"{'':<10} {'boxes':>6} {'near-white':>10} {'saturation':>10} {'hue':>6} {'red':>6}")
    for name, c in measured.items():
        path, split = sides[name]
        where = f"{path}" + (f" ({split})" if split else "")
        line = f"{c.boxes:>6} {100 * c.white:>9.1f}% {c.saturation:>10.2f} {c.hue:>5.0f}° {100 * c.red:>5.1f}%"
        print(f"{name:<10} {line}  {where}")
    return 0


def _add_pair(p: argparse.ArgumentParser, synthetic_help: str, real_help: str) -> None:
    """The SYNTHETIC and REAL positionals of a command comparing two sets (required unless --print-config), and a
    split option for each."""
    p.add_argument("synthetic", type=Path, nargs="?", metavar="SYNTHETIC", help=synthetic_help)
    p.add_argument("real", type=Path, nargs="?", metavar="REAL", help=real_help)
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
        "GrabCut cut-out mask of every --class box (the rule and settings of synth cutouts), on both sides.\n\n"
        "example:\n  fuzzyfire synth colour out/m2 ../shared/data/fire-cctv-416 --real-split train\n"
        "  fuzzyfire synth colour out/m2-exposed out/curated --real-split train --json",
    )
    _add_pair(p, "synthetic dataset, any labelled format", "real dataset, any labelled format")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    add_settings(p, _cutout_config, COLOUR_ALIASES, cmd_colour, section="synth cutouts", flag="--config")


def _cutout_config() -> type:
    from synth.flames.cutouts import CutoutConfig

    return CutoutConfig


def _scenes_config() -> type:
    from synth.places.scenes import ScenesConfig

    return ScenesConfig


def _gap_config() -> type:
    from synth.gap import GapConfig

    return GapConfig


def _flame_library_config() -> type:
    from synth.flames.library import FlameLibraryConfig

    return FlameLibraryConfig


def _method1_config() -> type:
    from synth.method1 import Method1Config

    return Method1Config


def _method2_config() -> type:
    from synth.method2 import Method2Config

    return Method2Config


def _register_flames(sub: argparse._SubParsersAction) -> None:
    p = add_command(
        sub,
        "flames",
        help="simulate procedural flame sprite sequences",
        description="Simulate flame sequences (stable fluids or noise), keep every K-th frame. Each sequence is a\n"
        "folder of NNNN_emission.png (the flame's light on black), NNNN_mask.png and, for frames with smoke,\n"
        "NNNN_smoke.png (RGBA); preview.png shows every sequence composited over a dark and a light background.\n"
        "Settings: a flames section (synth.flames.library.FlameLibraryConfig), the options below, or --set KEY=VALUE.\n\n"
        "example:\n  fuzzyfire synth flames --out out/flames --n 12 --seed 0 --frames 1024\n"
        "  fuzzyfire synth flames --out out/flames-exposed --exposed --set rare=0",
    )
    p.add_argument("--out", required=True, type=Path, help="folder for the sequence folders")
    add_settings(p, _flame_library_config, FLAME_ALIASES, cmd_flames, section="flame library")


def _register_cutouts(sub: argparse._SubParsersAction) -> None:
    from ground.cli.commands import add_reader_args

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
    p.add_argument("src", nargs="?", metavar="SRC", help="labelled dataset folder (any layout fuzzyfire reads)")
    p.add_argument("--out", type=Path, help="new folder for the sequence folders (required unless --print-config)")
    p.add_argument("--split", help="only this split (default: every image)")
    add_reader_args(p, source=False)
    add_settings(p, _cutout_config, CUTOUT_ALIASES, cmd_cutouts, flag="--config")


def _register_scenes(sub: argparse._SubParsersAction) -> None:
    p = add_command(
        sub,
        "scenes",
        help="render one preview per procedural environment",
        description="Render a preview PNG of each of the first N environments.\n\n"
        "example:\n  fuzzyfire synth scenes --out out/scenes --n 48 --size 320x240",
    )
    p.add_argument("--out", type=Path, help="folder for the preview PNGs (required unless --print-config)")
    add_settings(p, _scenes_config, SCENES_ALIASES, cmd_scenes)


def _dataset_arguments(
    p: argparse.ArgumentParser,
    schema: Callable[[], type],
    aliases: Sequence[Alias],
    func: Callable[[argparse.Namespace], int],
) -> None:
    """Method 1 and Method 2's options: the run's own (--out, --overwrite, --workers), then the settings
    (``schema`` imports the config class only when the help is printed) and ``func``, what the command runs."""
    p.add_argument("--out", type=Path, help="output dataset folder (required unless --print-config)")
    p.add_argument("--overwrite", action="store_true", help="replace a fuzzyfire dataset already at --out")
    p.add_argument(
        "--workers",
        type=int,
        help="image processes (default: one per core; any number writes the same bytes)",
    )
    p.add_argument(
        "--executor",
        choices=EXECUTOR_CHOICES,
        help="local (the default: --workers processes) or ray (blocks of views as Ray tasks; the same bytes; --out on "
        "storage every node sees)",
    )
    p.add_argument("--address", help="with --executor ray: a running cluster (HOST:6379); default a local Ray")
    add_settings(p, schema, aliases, func)


def _register_method1(sub: argparse._SubParsersAction) -> None:
    p = add_command(
        sub,
        "method1",
        help="Method 1: flame planes in the 3D scenes (paper boxes vs visible boxes)",
        description="Place flame image planes in the rendered environments (camera rules as in the paper)\n"
        "and annotate them with the visible box (segmentation pass + warped flame mask, occlusion\n"
        "handled) or the paper's box (projected plane corners, clipped). Both box sets are kept in\n"
        "masks/box_modes.json; `synth audit` reports both. Resumes an interrupted run. Settings: CONFIG.yaml\n"
        "(configs/synth-method1.yaml lists every key), the options below, then --set KEY=VALUE.\n\n"
        "example:\n  fuzzyfire synth method1 --n 1000 --seed 0 --out out/m1 --size 640x480\n"
        "  fuzzyfire synth method1 --n 200 --out out/m1-paper --box-mode paper\n"
        "  fuzzyfire synth method1 configs/synth-method1.yaml --set n=200 --out out/m1-yaml\n"
        "  fuzzyfire synth audit out/m1 --json",
    )
    _dataset_arguments(p, _method1_config, METHOD1_ALIASES, cmd_method1)


def _register_method2(sub: argparse._SubParsersAction) -> None:
    p = add_command(
        sub,
        "method2",
        help="Method 2: composite flames on rendered views, photos and panoramas (exact boxes)",
        description="Render environment views once and composite flame sprites on them; boxes come\n"
        "from each flame's final visible mask. Places: procedural rooms, 3D files and 360-degree panoramas\n"
        "(--environments), your fire-free photos (--backgrounds), your labelled frames (--labelled-frames).\n"
        "Resumes an interrupted run. Settings: CONFIG.yaml (configs/synth-method2.yaml lists every key), the options\n"
        "below, then --set KEY=VALUE.\n\n"
        "example:\n  fuzzyfire synth method2 --n 200 --out out/m2 --size 416x416\n"
        "  fuzzyfire synth method2 --n 200 --out out/m2-photos --backgrounds ../shared/data/fire-free\n"
        "  fuzzyfire synth method2 --n 200 --out out/m2-panoramas --environments ../shared/data/panoramas\n"
        "  fuzzyfire synth method2 --n 200 --out out/m2-rooms --environments configs/scenes\n"
        "  fuzzyfire synth method2 --n 200 --out out/m2-frames --labelled-frames my/cctv-labelled  # keeps their boxes\n"
        "  fuzzyfire synth method2 configs/synth-method2.yaml --set n=200 --set flames.exposed=true --out out/m2-yaml\n"
        "  fuzzyfire synth audit out/m2 --json",
    )
    _dataset_arguments(p, _method2_config, METHOD2_ALIASES, cmd_method2)


def _register_audit(sub: argparse._SubParsersAction) -> None:
    p = add_command(
        sub,
        "audit",
        help="IoU of written boxes vs pixel-truth mask boxes, and the boxed flames' visibility",
        description="Compare a synthetic dataset's boxes with the boxes of its kept flame masks; for Method 2,\n"
        "also the boxed flames' contrast against the flame-free background (ΔE*ab, min and median) and how\n"
        "many flames were erased because nobody could see them (synth/compose/visibility.py).\n\n"
        "example:\n  fuzzyfire synth audit out/m2 --json",
    )
    p.add_argument("folder", type=Path, help="a dataset written by synth method1 or method2")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=cmd_audit)


def _register_gap(sub: argparse._SubParsersAction) -> None:
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
    p.add_argument("--json", action="store_true", help="print one JSON object")
    add_cache_args(p)
    add_settings(p, _gap_config, GAP_ALIASES, cmd_gap, flag="--config")


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
