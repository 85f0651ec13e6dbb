import pytest

from centerart.utils.atomic import atomic_directory, remove_stale_temporaries
from centerart.utils.seeding import item_seed


def test_atomic_directory_leaves_nothing_on_error(tmp_path):
    final = tmp_path / "item"
    with pytest.raises(RuntimeError), atomic_directory(final) as tmp:
        (tmp / "half.txt").write_text("x")
        raise RuntimeError("crash")
    assert not final.exists()
    assert list(tmp_path.iterdir()) == []


def test_atomic_directory_commits(tmp_path):
    final = tmp_path / "item"
    with atomic_directory(final) as tmp:
        (tmp / "a.txt").write_text("x")
    assert (final / "a.txt").read_text() == "x"
    (tmp_path / ".tmp-item-stale").mkdir()
    assert remove_stale_temporaries(tmp_path) == 1
    assert final.exists()


def test_item_seed_is_stable_and_keyed():
    assert item_seed(0, "oven", 3) == item_seed(0, "oven", 3)
    assert item_seed(0, "oven", 3) != item_seed(0, "oven", 4)
    assert item_seed(1, "oven", 3) != item_seed(0, "oven", 3)
