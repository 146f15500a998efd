from pathlib import Path

import pytest

from synth.flames.library import FlameLibraryConfig
from synth.method2 import Method2Config
from synth.schema import check_range, to_json


def test_check_range():
    check_range("x", (0.5, 0.5))
    check_range("x", (0.2, 3.0), 0.2)
    for bad, low in (((2.0, 1.0), None), ((0.1, 1.0), 0.2), ((1.0,), None)):
        with pytest.raises(ValueError, match="x must be"):
            check_range("x", bad, low)


def test_to_json_is_plain_data():
    cfg = Method2Config(flames=FlameLibraryConfig(folders=(Path("a/b"),)))
    data = to_json(cfg)
    assert data["flame_height_m"] == [0.3, 2.5] and data["flames"]["folders"] == ["a/b"]
    import json

    assert json.loads(json.dumps(data)) == data
