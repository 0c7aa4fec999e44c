"""Files written whole or not at all (catenary_sim._files): what the studies, comparisons and
calibrations write gets the mode a plain open() gives under the umask (mkstemp's 0600 would hide
a calibration's results from the group), replaces an old file whole, and leaves no staging file
when the write fails."""
import os

import pytest

from catenary_sim import _files


def test_a_file_is_written_whole_with_the_umasks_mode(tmp_path):
    old = os.umask(0o027)
    try:
        path = tmp_path / "out.json"
        path.write_text("old")
        _files.write_atomically(str(path), "new")
        assert path.read_text() == "new"
        assert os.stat(path).st_mode & 0o777 == 0o640
    finally:
        os.umask(old)
    assert os.listdir(tmp_path) == ["out.json"]  # no staging file left


def test_a_failed_write_leaves_the_old_file_and_no_staging_file(tmp_path):
    path = tmp_path / "out.json"
    path.write_text("old")
    with pytest.raises(TypeError):
        _files.write_atomically(str(path), object())  # not text: the write itself fails
    assert path.read_text() == "old"
    assert os.listdir(tmp_path) == ["out.json"]
