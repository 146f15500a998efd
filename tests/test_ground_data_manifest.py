import hashlib

from ground.data.manifest import build_manifest, file_sha256, versions


def test_sha256_and_sorted_sources(tmp_path):
    (tmp_path / "b.txt").write_bytes(b"bee")
    (tmp_path / "a.txt").write_bytes(b"ay")
    assert file_sha256(tmp_path / "a.txt") == hashlib.sha256(b"ay").hexdigest()
    man = build_manifest("cmd", {"out": tmp_path, "n": 3}, [tmp_path / "b.txt", tmp_path / "a.txt", tmp_path / "a.txt"])
    assert [s["path"].rsplit("/", 1)[-1] for s in man["sources"]] == ["a.txt", "b.txt"]
    assert man["args"] == {"n": 3, "out": tmp_path.as_posix()}
    assert versions()["python"].count(".") == 2
