"""The resumable generation loop that Method 1 and Method 2 share: stage image ``i`` for every ``i`` in
``range(cfg.n)`` not yet staged, from views rendered once per (scene, camera) and cached, then write the dataset.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from curate.core.progress import progress
from curate.core.writer import WriteResult, check_output_target
from synth import render
from synth.envfile import find_environment_files
from synth.kits import credits, find_kits, licence_files, load_kit
from synth.panorama import PanoramaBackgrounds
from synth.photos import PhotoBackgrounds, keep_in_pool
from synth.places import split_places
from synth.schema import to_json
from synth.sprites import SpriteSequence
from synth.staging import Staging, finish
from synth.views import ViewCache

MakeImage = Callable[[Any, int, Sequence[SpriteSequence], ViewCache], tuple]


def generate(
    method: str,
    cfg: Any,
    make_image: MakeImage,
    library: Sequence[SpriteSequence],
    out: Path,
    overwrite: bool = False,
    platform: str | None = None,
) -> WriteResult:
    """Generate (or resume) ``cfg.n`` images with ``make_image(cfg, i, library, views)`` and write ``out``.

    ``method`` names the source tag (``synth:<method>``) and the command in the manifest; ``cfg`` is a
    Method1Config or Method2Config (``n``, ``seed``, ``scenes``, ``environments``, ``streets``, ``kits``, ``width``,
    ``height``, ``smoke_class``). With kit streets the manifest credits the kits (``args.kit_credits``) and lists
    their licence files among its ``sources``. The output folder, the environment files, the kits and the
    background photos are checked before anything is rendered (:class:`~curate.core.writer.OutputError`,
    FileNotFoundError, ValueError). A run that fails or is interrupted
    keeps the images it finished in the staging folder and says so (the same command resumes from them); one
    that finished none leaves nothing behind.
    """
    if not library or not all(seq.sprites for seq in library):
        raise ValueError("the flame library is empty")
    check_output_target(out, overwrite)
    places = split_places(cfg.environments, getattr(cfg, "backgrounds", ()))  # backgrounds: Method 2 only
    if places.panoramas and method != "method2":
        raise ValueError(f"{places.panoramas[0]}: a panorama is a Method 2 place (Method 1 needs 3D meshes)")
    files = find_environment_files(places.meshes) if places.meshes else []
    kit_folders = find_kits(cfg.kits) if getattr(cfg, "streets", 0) else []  # Method 1 and 2 configs have them
    photo_files = keep_in_pool(places.photos, getattr(cfg, "background_holdout", 0.0))
    args = {**to_json(cfg), "flame_sequences": [s.name for s in library]}
    if kit_folders:
        args["kit_credits"] = credits(kit_folders)
    staging = Staging(out, args)
    try:
        with render.Renderer(cfg.width, cfg.height, platform) as renderer:
            photos = PhotoBackgrounds(photo_files, cfg.width, cfg.height, cfg.seed) if photo_files else None
            panoramas = (
                PanoramaBackgrounds(places.panoramas, cfg.width, cfg.height, cfg.seed) if places.panoramas else None
            )
            share, count = getattr(cfg, "photo_share", 0.0), -(-cfg.n // cfg.images_per_view)  # views of the run
            views = ViewCache(
                cfg.seed,
                cfg.scenes,
                renderer,
                files,
                photos,
                share,
                count,
                panoramas,
                getattr(cfg, "panorama_share", 0.5),
                surfaces=getattr(cfg, "stand", "anywhere") == "surfaces",  # Method 2's rule; Method 1 has its own
                kits=[load_kit(folder) for folder in kit_folders],
                streets_count=getattr(cfg, "streets", 0),
            )
            todo = [i for i in range(cfg.n) if not staging.done(i)]
            for i in progress(todo, total=len(todo), desc=f"{method} images"):
                staging.save(i, *make_image(cfg, i, library, views))
        for source in (photos, panoramas):
            for path, reason in (source.problems if source else {}).items():
                print(f"{path}: skipped background ({reason})", file=sys.stderr)
        sources = [path for folder in kit_folders for path in licence_files(folder)]
        return finish(staging, out, cfg.n, f"synth:{method}", f"synth {method}", args, cfg.smoke_class, overwrite,
                      sources)  # fmt: skip
    except BaseException:
        staging.abandon(cfg.n)
        raise
