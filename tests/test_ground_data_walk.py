import os

from ground.data.walk import walk, walk_files


def test_links_followed_once_and_hidden_skipped(tmp_path):
    elsewhere = tmp_path / "elsewhere"
    (elsewhere / "deep").mkdir(parents=True)
    (elsewhere / "a.jpg").write_bytes(b"a")
    (elsewhere / "deep" / "b.jpg").write_bytes(b"b")
    root = tmp_path / "root"
    (root / "train").mkdir(parents=True)
    os.symlink(elsewhere, root / "train" / "images")  # a linked folder (shared clusters)
    os.symlink(elsewhere / "a.jpg", root / "linked.jpg")  # a linked file
    os.symlink("..", root / "train" / "loop")  # a loop back to root
    (root / ".hidden").mkdir()
    (root / ".hidden" / "c.jpg").write_bytes(b"c")
    (root / ".d.jpg").write_bytes(b"d")
    found = [p.relative_to(root).as_posix() for p in walk_files(root)]
    assert found == ["linked.jpg", "train/images/a.jpg", "train/images/deep/b.jpg"]
    folders = [folder.relative_to(root).as_posix() for folder, _, _ in walk(root)]
    assert folders == [".", "train", "train/images", "train/images/deep"]  # the loop back to root is not entered
    assert walk_files(root, lambda n: n.endswith(".png")) == []
