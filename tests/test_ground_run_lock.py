from importlib import metadata
from pathlib import Path

import pytest

from ground.data.manifest import build_manifest
from ground.run.lock import (
    LOCK_FILE,
    canonical_name,
    compare,
    default_lock_path,
    lock_status,
    lock_summary,
    parse_lock,
    same_version,
)


def test_parse_lock_reads_exact_pins_only():
    text = "# header\n\nJinja2==3.1.6\nml_dtypes==0.6.0  # comment\n-e /work/x\n"
    assert parse_lock(text) == {"jinja2": "3.1.6", "ml-dtypes": "0.6.0"}
    for bad in ("numpy>=1.24", "numpy", "numpy==", "numpy==2.*"):
        with pytest.raises(ValueError, match=f"{LOCK_FILE}:2: .*not an exact pin"):
            parse_lock(f"# x\n{bad}\n")


def test_versions_compare_like_pip():
    assert canonical_name("Typing_Extensions") == "typing-extensions"
    assert same_version("2.13.0", "2.13.0+cpu") and same_version("1.0", "1.0")
    assert not same_version("2.13.0", "2.13.1") and not same_version("1.0", None)
    assert compare({"a": "1", "b": "2"}, {"a": "1", "b": "3"}) == {"b": {"locked": "2", "installed": "3"}}


def test_lock_status_names_what_differs(tmp_path: Path):
    numpy = metadata.version("numpy")
    good, bad = tmp_path / "good.lock", tmp_path / "bad.lock"
    good.write_text(f"numpy=={numpy}\n", encoding="utf-8")
    bad.write_text(f"numpy=={numpy}\nno-such-package-xyz==1.0\npytest==0.0.1\n", encoding="utf-8")
    assert lock_status(good)["matches"] is True
    status = lock_status(bad)
    assert status["matches"] is False and status["packages"] == 3
    assert status["differs"] == {
        "no-such-package-xyz": {"locked": "1.0", "installed": None},
        "pytest": {"locked": "0.0.1", "installed": metadata.version("pytest")},
    }
    assert "no-such-package-xyz missing (locked 1.0)" in lock_summary(status)
    assert lock_status(tmp_path / "absent.lock") == {"file": None, "matches": None}


def test_this_environment_is_the_locked_one():
    """`make install` (make test, CI) installs every package at requirements.lock's version."""
    status = lock_status(default_lock_path())
    assert status["file"] == LOCK_FILE, "requirements.lock is missing from the checkout"
    assert status["matches"], lock_summary(status)


def test_manifests_record_the_lock(tmp_path: Path):
    manifest = build_manifest("cmd", {}, [])
    assert manifest["lock"] == lock_status()
    assert manifest["lock"]["file"] == LOCK_FILE
