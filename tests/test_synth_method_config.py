"""The settings Method 1 and Method 2 share: one base both inherit; their places are read through places() (Method
1: environments only), their path keys are every tuple of paths, a key of the other method is refused at load."""

from __future__ import annotations

from pathlib import Path

import pytest

from ground.config.loader import ConfigError, build_config
from synth.method1 import Method1Config
from synth.method2 import Method2Config
from synth.method_config import MethodConfig, PoolPlaces


def test_both_methods_share_one_base_and_name_themselves() -> None:
    assert issubclass(Method1Config, MethodConfig) and issubclass(Method2Config, MethodConfig)
    assert (Method1Config.method, Method2Config.method) == ("method1", "method2")
    assert not Method1Config.composited and Method2Config.composited
    assert (Method1Config().images_per_view, Method2Config().images_per_view) == (1, 8)  # each method's default


def test_places_are_typed_and_method1_has_environments_only() -> None:
    m1 = Method1Config(environments=(Path("rooms"),))
    assert m1.places() == PoolPlaces(environments=(Path("rooms"),))
    m2 = Method2Config(backgrounds=(Path("photos"),), labelled_frames=(Path("cams"),), background_holdout=0.25)
    assert m2.places() == PoolPlaces((), (Path("photos"),), (Path("cams"),), 0.25, 0.5, 0.5)
    assert m2.scenes == 0 and Method2Config().scenes == 48  # places of your own: no procedural room


def test_path_keys_are_every_tuple_of_paths_and_resolve_together() -> None:
    assert Method1Config().place_keys() == ("environments",)
    assert Method2Config().place_keys() == ("environments", "backgrounds", "labelled_frames")
    m2 = Method2Config(environments=(Path("p"),), backgrounds=("b",), labelled_frames=(Path("/abs/f"),))
    moved = m2.with_paths(lambda p: p if p.is_absolute() else Path("/base") / p)
    assert moved.places().environments == (Path("/base/p"),) and moved.backgrounds == (Path("/base/b"),)
    assert moved.labelled_frames == (Path("/abs/f"),) and moved.with_paths(lambda p: p) == moved


def test_a_key_of_the_other_method_or_an_old_name_is_refused_at_load() -> None:
    with pytest.raises(ConfigError, match="backgrounds: unknown key"):
        build_config({"backgrounds": ["photos"]}, Method1Config)
    with pytest.raises(ConfigError, match="frames: unknown key"):
        build_config({"frames": ["cams"]}, Method2Config)  # renamed labelled_frames: never silently ignored


@pytest.mark.parametrize(
    ("schema", "message"),
    [
        (Method1Config, "scenes is 0 and no environments are given: nothing to render"),
        (Method2Config, "no environments, backgrounds, labelled_frames or own_frames are given: nothing to composite"),
    ],
)
def test_no_place_at_all_is_refused(schema: type, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        schema(scenes=0)
