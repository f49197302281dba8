"""The atomic writer every output goes through (``replication/_io.py``) in a folder it cannot write:
an error, no file, no temporary."""
import pytest

from replication import _io


def test_a_read_only_folder_refuses_the_write_and_leaves_nothing(locked):
    """:func:`replication._io.write_atomic` in a folder it cannot write: an ``OSError``, no file, no
    temporary."""
    with pytest.raises(PermissionError, match="Permission denied"):
        _io.write_atomic(locked / "r.json", "{}")
    assert not list(locked.iterdir())
