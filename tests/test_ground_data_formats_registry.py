import pytest
from factories import write_image, write_yolo_dataset

from ground.data.formats.registry import detect_format, read_dataset


def test_detects_each_format(tmp_path):
    write_yolo_dataset(tmp_path / "yolo")
    assert detect_format(tmp_path / "yolo") == "yolo"
    (tmp_path / "voc" / "Annotations").mkdir(parents=True)
    assert detect_format(tmp_path / "voc") == "voc"
    (tmp_path / "coco").mkdir()
    (tmp_path / "coco" / "annotations.json").write_text('{"images": []}')
    assert detect_format(tmp_path / "coco") == "coco"
    assert detect_format(tmp_path / "coco" / "annotations.json") == "coco"


def test_images_alone_are_a_negatives_only_set_and_nothing_is_undetectable(tmp_path):
    write_image(tmp_path / "only" / "x.jpg", 5, 5)
    assert detect_format(tmp_path / "only") == "images"
    result = read_dataset(tmp_path / "only")
    assert len(result.dataset.images) == 1 and not result.dataset.annotations and not result.dataset.categories
    assert result.unlabelled == {1} and [p.code for p in result.problems] == ["negatives-only"]
    (tmp_path / "empty" / "sub").mkdir(parents=True)
    with pytest.raises(ValueError, match="no images, labels or annotations found"):
        detect_format(tmp_path / "empty")
    with pytest.raises(FileNotFoundError):
        detect_format(tmp_path / "nothing")
    write_yolo_dataset(tmp_path / "yolo")
    with pytest.raises(ValueError, match="unknown format 'kitti'"):
        read_dataset(tmp_path / "yolo", "kitti")


def test_drop_classes_silences_their_unknown_class_warning(tmp_path):
    write_yolo_dataset(tmp_path / "ds", names=("Fire", "Default"))
    result = read_dataset(tmp_path / "ds")
    assert [p.code for p in result.problems if p.code and p.level != "info"] == ["unknown-class:default"]
    dropped = result.drop_classes(["DEFAULT"])
    assert dropped.dataset.category_names == ["fire"] and len(dropped.dataset.annotations) == 2
    assert not [p for p in dropped.problems if p.level == "warning"]
    assert any(p.reason == "dropped 1 boxes of class 'default' as asked" for p in dropped.problems)
    assert not any("now images without boxes" in p.reason for p in dropped.problems)  # image a keeps its fire
    no_fire = result.drop_classes(["fire"])  # image b had only a fire box: its new role is said
    assert any(p.reason == "1 images had only boxes of fire and are now images without boxes (negatives)"
               for p in no_fire.problems)  # fmt: skip
    assert result.drop_classes([]) is result and result.dataset.category_names == ["fire", "default"]


def test_aliases_must_name_a_class_of_the_source_in_any_spelling(tmp_path):
    from ground.data.names import UnknownNameError

    write_yolo_dataset(tmp_path / "ds", names=("Flame_Big", "Default"))
    result = read_dataset(tmp_path / "ds", aliases={"flame big": "fire"})
    assert result.source_classes == ("Flame_Big", "Default") and "fire" in result.dataset.category_names
    assert result.check_aliases({"flame big": "fire", "DEFAULT": "smoke"}) is result and result.check_aliases(None)
    with pytest.raises(UnknownNameError, match=r"--alias 'Flames': no such class \(classes: 'Flame_Big', 'Default'\)"):
        result.check_aliases({"Flames": "fire"})
    with pytest.raises(UnknownNameError, match=r"aliases 'smok'"):
        result.check_aliases({"smok": "smoke"}, option="aliases")
    assert result.drop_classes(["default"]).source_classes == result.source_classes


def test_drop_classes_takes_comma_lists_and_refuses_names_that_match_nothing(tmp_path):
    from ground.data.names import UnknownNameError

    write_yolo_dataset(tmp_path / "ds", names=("Fire", "Default"))
    result = read_dataset(tmp_path / "ds")
    dropped = result.drop_classes(["default,fire"])
    assert dropped.dataset.category_names == [] and not dropped.dataset.annotations
    with pytest.raises(UnknownNameError, match=r"--drop-class 'smok': no such class \(classes: 'fire', 'default'\)"):
        result.drop_classes(["default,smok"])
    kept = result.drop_classes(["smok"], missing_ok=True)  # the caller checked the name against other datasets
    assert kept is result


def test_a_classification_layout_is_detected_and_a_label_only_declares_a_folder_without_labels(tmp_path):
    write_image(tmp_path / "layout" / "fire" / "a.jpg", 5, 5)
    write_image(tmp_path / "layout" / "normal" / "b.jpg", 5, 5, seed=1)
    assert detect_format(tmp_path / "layout") == "folders"
    assert [i.labels for i in read_dataset(tmp_path / "layout").dataset.images] == [("fire",), ()]
    assert [i.labels for i in read_dataset(tmp_path / "layout" / "fire", label="fire").dataset.images] == [("fire",)]
    with pytest.raises(ValueError, match="its folders name the classes"):
        read_dataset(tmp_path / "layout", label="fire")
    write_yolo_dataset(tmp_path / "yolo")
    with pytest.raises(ValueError, match=r"label: fire declares a folder of images without label files.*has labels"):
        read_dataset(tmp_path / "yolo", label="fire")
