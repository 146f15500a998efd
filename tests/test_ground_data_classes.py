from ground.data.classes import canonical_class, is_known, normalise_name


def test_synonyms_and_case():
    assert canonical_class("Fire") == "fire" and canonical_class("FLAMES") == "fire"
    assert canonical_class(" Smoke ") == "smoke" and canonical_class("fire_flame") == "fire"


def test_unknown_kept_normalised_and_user_aliases():
    assert canonical_class("Default") == "default" and not is_known("default")
    assert canonical_class("big-blaze", {"Big Blaze": "Fire"}) == "fire"
    assert normalise_name("A__b  c") == "a b c"
