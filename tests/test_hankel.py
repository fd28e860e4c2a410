"""Block-Hankel construction: shapes, entries, permutation, and clear errors on bad input."""
import numpy as np
import pytest

from ident.hankel import block_hankel, mosaic_hankel, time_major_permutation


def test_entries_follow_the_definition() -> None:
    w = np.arange(12.0).reshape(6, 2)  # T = 6, q = 2
    H = block_hankel(w, 3)
    assert H.shape == (6, 4)
    for lag in range(3):
        for var in range(2):
            np.testing.assert_array_equal(H[lag * 2 + var], w[lag:lag + 4, var])


def test_result_does_not_alias_input() -> None:
    w = np.ones((5, 1))
    H = block_hankel(w, 2)
    H[0, 0] = 7.0
    assert w[0, 0] == 1.0


def test_permutation_is_a_permutation() -> None:
    perm = time_major_permutation(3, 4)
    assert sorted(perm) == list(range(12))
    assert perm[1] == 4 and perm[3] == 1  # lag 0 of variable 1; lag 1 of variable 0


@pytest.mark.parametrize("w, depth, error, words", [
    (np.ones(5), 2, ValueError, "w must be a 2-D array"),
    (np.ones((5, 2)), 6, ValueError, "1 <= depth <= T = 5"),
    (np.ones((5, 2)), 0, ValueError, "depth"),
    (np.ones((5, 2)), 2.0, TypeError, "depth must be an integer"),
])
def test_bad_input(w, depth, error, words) -> None:
    with pytest.raises(error, match=words):
        block_hankel(w, depth)


def test_mosaic_rejects_mismatched_widths() -> None:
    with pytest.raises(ValueError, match="same number of columns"):
        mosaic_hankel([np.ones((5, 2)), np.ones((5, 3))], 2)
    with pytest.raises(ValueError, match="at least one"):
        mosaic_hankel([], 2)
