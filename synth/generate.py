"""The resumable generation loop that Method 1 and Method 2 share: stage image ``i`` for every ``i`` in
``range(cfg.n)`` not yet staged, from views rendered once per (scene, camera) and cached, then write the dataset.
The loop reads a :class:`synth.method_config.MethodConfig` (its places through :meth:`~synth.method_config.
MethodConfig.places`) and makes images with the config's method (:func:`image_maker`).
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator, Sequence
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2

from ground.data.writer import WriteResult, check_output_target
from ground.run.cluster import Cluster
from ground.run.progress import progress
from synth import method1, method2
from synth.flames.sprites import SpriteSequence
from synth.method_config import MethodConfig
from synth.places import render
from synth.places.envfile import EnvironmentFile, find_environment_files
from synth.places.frames import FrameLabels, frame_classes, load_frames
from synth.places.panorama import PanoramaBackgrounds
from synth.places.photos import PhotoBackgrounds, keep_in_pool
from synth.places.views import ViewCache, environment_index
from synth.schema import to_json
from synth.staging import Staging, finish

#: ``make_image(cfg, i, library, views)`` -> (image, fire masks, record, smoke masks or None): one image of a method.
MakeImage = Callable[[Any, int, Sequence[SpriteSequence], ViewCache], tuple]

#: Views per block of a run without mesh files (a process makes whole blocks).
BLOCK_VIEWS = 8
#: Images to make per extra process at least (starting one costs ~2 s): fewer run in this process.
MIN_IMAGES_PER_WORKER = 16


@dataclass(frozen=True)
class Job:
    """What a process needs to make images of a run (picklable): the config and its image maker, the flame
    library, the output folder (its staging folder receives the images) and the checked places."""

    cfg: MethodConfig
    make_image: MakeImage
    library: tuple[SpriteSequence, ...]
    out: Path
    platform: str | None
    files: tuple[EnvironmentFile, ...]
    photo_files: tuple[Path, ...]
    panoramas: tuple[Path, ...]
    frames: dict[Path, FrameLabels] = field(default_factory=dict)  # labelled frames' boxes by class, by photo


@contextmanager
def opened_views(job: Job) -> Iterator[tuple[ViewCache, list[dict[str, str]]]]:
    """The run's :class:`ViewCache` on a fresh renderer (closed on exit) and the ``problems`` dicts of its
    photo and panorama backgrounds (unreadable files: reason)."""
    cfg, places = job.cfg, job.cfg.places()
    with render.Renderer(cfg.width, cfg.height, job.platform) as renderer:
        photos = (
            PhotoBackgrounds(list(job.photo_files), cfg.width, cfg.height, cfg.seed, job.frames)
            if job.photo_files
            else None
        )
        panoramas = PanoramaBackgrounds(list(job.panoramas), cfg.width, cfg.height, cfg.seed) if job.panoramas else None
        count = -(-cfg.n // cfg.images_per_view)  # views of the run
        views = ViewCache(
            cfg.seed,
            cfg.scenes,
            renderer,
            job.files,
            photos,
            places.photo_share,
            count,
            panoramas,
            places.panorama_share,
            surfaces=cfg.composited,  # Method 2's flames stand on surfaces; Method 1 has its own rule
        )
        yield views, [source.problems for source in (photos, panoramas) if source is not None]


def run_library(cfg: MethodConfig, cutouts: Sequence[SpriteSequence] = ()) -> list[SpriteSequence]:
    """The sequences a run of ``cfg`` draws from: the flames of ``cfg.flames`` (its cut-outs: the flame sequences
    among ``cutouts``, :func:`synth.flames.library.build_library`) and, for Method 2, the plumes of ``cfg.smoke``
    (its cut-outs: the smoke sequences among ``cutouts`` and among the folders of ``flames.folders``, as
    ``fuzzyfire synth cutouts --class smoke`` writes them; :func:`synth.smoke.library.smoke_library`). ValueError
    when smoke cut-outs are given to a run that lays none (Method 1, no plumes, or ``smoke.source`` simulated) or
    no flame is left."""
    from synth.flames.library import build_library
    from synth.smoke.library import smoke_library, split_library

    flames, smoke = split_library(cutouts)
    library, folder_smoke = split_library(build_library(cfg.flames, flames))
    smoke += folder_smoke
    m2 = isinstance(cfg, method2.Method2Config)
    if smoke and not (m2 and cfg.smoke.plumes and cfg.smoke.source == "cutouts"):  # type: ignore[union-attr]
        names = ", ".join(s.name for s in smoke[:3]) + (" ..." if len(smoke) > 3 else "")
        raise ValueError(
            f"smoke cut-outs given ({names}) but the run lays no plumes of them: they are Method 2 plumes with "
            "smoke.source cutouts and smoke.above or smoke.alone above 0"
        )
    if not library:
        raise ValueError("the flame library is empty: the flame folders hold smoke cut-outs only (give flames too)")
    return library + smoke_library(cfg.smoke, smoke) if m2 else library  # type: ignore[union-attr]


def _make_images(job: Job, todo: Sequence[int]) -> dict[str, str]:
    """Make and stage images ``todo`` in this process (a progress bar); the backgrounds skipped, with reasons."""
    staging = Staging(job.out)
    with opened_views(job) as (views, problems):
        for i in progress(todo, total=len(todo), desc=f"{job.cfg.method} images"):
            staging.save(i, *job.make_image(job.cfg, i, job.library, views))
        return {k: v for found in problems for k, v in found.items()}


def blocks(job: Job, todo: Sequence[int]) -> list[list[int]]:
    """``todo`` (ascending image indices) cut into blocks a process makes alone: the images of one mesh file's
    views (each environment is loaded by one process), else of :data:`BLOCK_VIEWS` views."""
    cfg = job.cfg
    per_view = cfg.images_per_view
    if job.files:
        views = -(-cfg.n // per_view)
        key = [environment_index(i // per_view, len(job.files), cfg.scenes, views) for i in todo]
    else:
        key = [i // per_view // BLOCK_VIEWS for i in todo]
    out: dict[int, list[int]] = {}
    for k, i in zip(key, todo):
        out.setdefault(k, []).append(i)
    return list(out.values())


_WORKER: dict[str, Any] = {}  # a worker process's job, its views and their problems (set by _start_worker)


def _start_worker(job: Job, token: str = "") -> None:
    """Open ``job``'s views in this worker process (spawned, or a Ray worker; ``token`` names the job) for the
    blocks it will make; a previous job's views and renderer are closed first."""
    import atexit

    if "stack" in _WORKER:
        _WORKER["stack"].close()
    else:
        atexit.register(lambda: _WORKER["stack"].close())
    cv2.setNumThreads(1)  # one image pipeline per core
    stack = ExitStack()
    views, problems = stack.enter_context(opened_views(job))
    _WORKER.update(job=job, views=views, problems=problems, staging=Staging(job.out), stack=stack, token=token)


def _work(block: Sequence[int]) -> tuple[int, dict[str, str]]:
    job, views = _WORKER["job"], _WORKER["views"]
    for i in block:
        _WORKER["staging"].save(i, *job.make_image(job.cfg, i, job.library, views))
    return len(block), {k: v for found in _WORKER["problems"] for k, v in found.items()}


def _ray_block(block: Sequence[int], job: Job, token: str) -> tuple[int, dict[str, str]]:
    """A Ray task: :func:`_work` on ``block``, the worker opening the job's views once (``token``) for all the
    blocks of the job it is given."""
    if _WORKER.get("token") != token:
        _start_worker(job, token)
    return _work(block)


def _collected(done: Iterator[tuple[int, dict[str, str]]], job: Job, total: int) -> dict[str, str]:
    """Wait for every block's ``(images made, backgrounds skipped with reasons)``, a progress bar over the
    ``total`` images; the skipped backgrounds of all blocks."""
    problems: dict[str, str] = {}

    def images_done() -> Iterator[int]:  # one item per finished image, for the progress bar
        for made, found in done:
            problems.update(found)
            yield from range(made)

    for _ in progress(images_done(), total=total, desc=f"{job.cfg.method} images"):
        pass
    return problems


def _in_workers(job: Job, todo: Sequence[int], workers: int) -> dict[str, str]:
    """Make and stage images ``todo`` in ``workers`` spawned processes, block by block (:func:`blocks`); the
    backgrounds skipped, with reasons. A failure in a process is raised here."""
    import multiprocessing

    chunks = blocks(job, todo)
    context = multiprocessing.get_context("spawn")  # no forked GL or torch state
    with context.Pool(min(workers, len(chunks)), _start_worker, (job,)) as pool:
        return _collected(pool.imap_unordered(_work, chunks), job, len(todo))


def _on_cluster(job: Job, todo: Sequence[int], cluster: Cluster) -> dict[str, str]:
    """Make and stage images ``todo`` on a Ray ``cluster``, one task per block (:func:`blocks`); the job goes
    to the object store once. The staging folder must be on storage every node sees at the same path."""
    import uuid

    done = cluster.map(_ray_block, blocks(job, todo), cluster.put(job), uuid.uuid4().hex)
    return _collected((result for _, result in done), job, len(todo))


def image_maker(cfg: MethodConfig) -> MakeImage:
    """The ``make_image`` of ``cfg``'s method (:mod:`synth.method1` or :mod:`synth.method2`); TypeError for
    another config."""
    makers: dict[type, MakeImage] = {
        method1.Method1Config: method1.make_image,
        method2.Method2Config: method2.make_image,
    }
    if type(cfg) not in makers:
        raise TypeError(f"no image maker for {type(cfg).__name__}: give make_image")
    return makers[type(cfg)]


def generate(
    cfg: MethodConfig,
    library: Sequence[SpriteSequence],
    out: Path,
    overwrite: bool = False,
    platform: str | None = None,
    workers: int = 1,
    cluster: Cluster | None = None,
    make_image: MakeImage | None = None,
) -> WriteResult:
    """Generate (or resume) ``cfg.n`` images of ``cfg``'s method (``make_image(cfg, i, library, views)``; None:
    the method's own, :func:`image_maker`) and write ``out``; returns the WriteResult.

    ``cfg.method`` names the source tag (``synth:<method>``) and the command in the manifest; its places are
    read through :meth:`~synth.method_config.MethodConfig.places`. The output folder, the environment files and
    the background photos are checked before anything is rendered (:class:`~ground.data.writer.OutputError`,
    FileNotFoundError, ValueError). A run that fails or is interrupted keeps the images it finished in the
    staging folder and says so (the same command resumes from them); one that finished none leaves nothing behind. ``workers`` > 1: images are made in up to that many processes (at
    least :data:`MIN_IMAGES_PER_WORKER` images each), each on whole blocks of views (:func:`blocks`); every image
    depends only on (seed, index), so the dataset is byte-identical to one process's. With a Ray ``cluster``
    the blocks are its tasks instead (``workers`` is not used): the same bytes again, ``out`` on shared storage.
    """
    make_image = make_image or image_maker(cfg)
    if not library or not all(seq.sprites for seq in library):
        raise ValueError("the flame library is empty")
    check_output_target(out, overwrite)
    given = cfg.places()
    places = given.split()
    if places.panoramas and not cfg.composited:
        raise ValueError(f"{places.panoramas[0]}: a panorama is a Method 2 place (Method 1 needs 3D meshes)")
    files = find_environment_files(places.meshes) if places.meshes else []
    photo_files = keep_in_pool(places.photos, given.background_holdout)
    unreadable: list = []
    # labelled frames: photos keeping their boxes (fire, and smoke when the pool boxes it)
    frames = load_frames(given.labelled_frames, unreadable, frame_classes(cfg.smoke_class))
    for problem in places.problems:  # unreadable files among the places and frames: named, never composited on
        print(f"{problem.path}: skipped background ({problem.reason})", file=sys.stderr)
    if note := places.panorama_note():
        print(note, file=sys.stderr)
    for problem in unreadable:
        print(problem, file=sys.stderr)
    known = set(photo_files)
    photo_files += [p for p in frames if p not in known]
    args = {**to_json(cfg), "flame_sequences": [s.name for s in library]}
    staging = Staging(out, args)
    job = Job(cfg, make_image, tuple(library), out, platform, tuple(files), tuple(photo_files),
              tuple(places.panoramas), frames)  # fmt: skip
    try:
        todo = [i for i in range(cfg.n) if not staging.done(i)]
        workers = min(workers, len(todo) // MIN_IMAGES_PER_WORKER)
        if cluster is not None:
            problems = _on_cluster(job, todo, cluster) if todo else {}
        elif workers > 1:
            problems = _in_workers(job, todo, workers)
        else:
            problems = _make_images(job, todo)
        for path, reason in problems.items():
            print(f"{path}: skipped background ({reason})", file=sys.stderr)
        return finish(
            staging, out, cfg.n, f"synth:{cfg.method}", f"synth {cfg.method}", args, cfg.smoke_class, overwrite
        )
    except BaseException:
        staging.abandon(cfg.n)
        raise
