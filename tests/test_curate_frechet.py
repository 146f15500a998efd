import numpy as np
import pytest

from curate.frechet import frechet_distance, gap_interval


def _reference(x: np.ndarray, y: np.ndarray) -> float:
    """The FID formula with an explicit matrix square root (symmetric form S1^1/2 S2 S1^1/2)."""
    s1, s2 = np.cov(x, rowvar=False), np.cov(y, rowvar=False)
    w, v = np.linalg.eigh(s1)
    root1 = (v * np.sqrt(np.clip(w, 0, None))) @ v.T
    cross = np.sqrt(np.clip(np.linalg.eigvalsh(root1 @ s2 @ root1), 0, None)).sum()
    return float(np.sum((x.mean(0) - y.mean(0)) ** 2) + np.trace(s1) + np.trace(s2) - 2 * cross)


@pytest.mark.parametrize(("n1", "n2", "d"), [(30, 40, 8), (12, 9, 50), (60, 7, 20)])
def test_matches_the_matrix_square_root_formula(n1, n2, d) -> None:
    rng = np.random.default_rng(0)
    x = rng.normal(size=(n1, d)) @ rng.normal(size=(d, d))
    y = rng.normal(1.0, 2.0, size=(n2, d))
    assert frechet_distance(x, y) == pytest.approx(
        _reference(x, y), rel=1e-6
    )  # the reference loses ~1e-8 in sqrt(tiny eigenvalues)


def test_exact_values() -> None:
    rng = np.random.default_rng(1)
    x = rng.normal(size=(25, 6))
    assert frechet_distance(x, x) == pytest.approx(0.0, abs=1e-9)
    shift = np.arange(6.0)
    assert frechet_distance(x, x + shift) == pytest.approx(float(shift @ shift), rel=1e-9)
    centred = x - x.mean(0)
    # S_y = 4 S_x: Tr S + 4 Tr S - 2 Tr(2 S) = Tr S
    assert frechet_distance(centred, 2 * centred) == pytest.approx(np.trace(np.cov(x, rowvar=False)), rel=1e-9)


def test_shape_errors() -> None:
    with pytest.raises(ValueError, match="same D"):
        frechet_distance(np.zeros((3, 2)), np.zeros((3, 4)))
    with pytest.raises(ValueError, match="at least 2"):
        frechet_distance(np.zeros((1, 2)), np.zeros((3, 2)))


def test_gap_separates_a_shifted_set_and_is_seeded() -> None:
    rng = np.random.default_rng(2)
    real = rng.normal(size=(120, 16))
    alike = rng.normal(size=(80, 16))
    shifted = rng.normal(0.5, 1.0, size=(80, 16))
    same = gap_interval(alike, real, np.random.default_rng(0), draws=40)
    far = gap_interval(shifted, real, np.random.default_rng(0), draws=40)
    assert same.size == 60 and same.draws == 40
    assert same.ratio.low < 1.0 < same.ratio.high and far.ratio.low > same.ratio.high  # alike: at the floor
    assert same.floor.low <= same.floor.median <= same.floor.high
    assert far.floor == gap_interval(shifted, real, np.random.default_rng(0), draws=40).floor
    assert far == gap_interval(shifted, real, np.random.default_rng(0), draws=40)


def test_gap_size_errors() -> None:
    with pytest.raises(ValueError, match="2 x size"):
        gap_interval(np.zeros((10, 3)), np.zeros((10, 3)), np.random.default_rng(0), size=6)
    with pytest.raises(ValueError, match="draws"):
        gap_interval(np.zeros((10, 3)), np.zeros((10, 3)), np.random.default_rng(0), draws=0)
