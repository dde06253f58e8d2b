"""A synthesis' search settings (mixdyn.synthesis.SearchSettings): counts below 1, or not
whole, are input errors naming their field; whole numbers of any integer type are kept as
ints; a chunk is at most the starts."""

import numpy as np
import pytest

from mixdyn.errors import ModelError
from mixdyn.synthesis import SearchSettings


@pytest.mark.parametrize(
    "field, value", [("starts", 0), ("chunk", -1), ("max_steps", 2.5), ("keep", "ten")]
)
def test_bad_counts_are_refused_by_name(field, value):
    with pytest.raises(ModelError, match=f"{field} must be a whole number") as e:
        SearchSettings(**{field: value})
    assert e.value.element == field


def test_whole_numbers_are_kept_and_the_chunk_is_at_most_the_starts():
    s = SearchSettings(starts=np.int64(64), chunk=512.0, seed=np.int32(3))
    assert (s.starts, s.chunk, s.seed) == (64, 512, 3)
    assert all(type(x) is int for x in (s.starts, s.chunk, s.seed))
    assert s.chunk_size == 64 and SearchSettings(starts=2048).chunk_size == 512
