"""Files written whole or not at all (the studies', comparisons' and calibrations' outputs): the
text goes to a new file beside its place, flushed to disk, and is renamed into place, so that a
reader sees the old file or the new one, never half of one."""
import os
import tempfile


def umask():
    """The process's umask (read by setting it and putting it back)."""
    m = os.umask(0)
    os.umask(m)
    return m


def stage(path, text):
    """TEXT in a new file beside PATH, on disk, with the mode a plain open() would give it (mkstemp
    makes it 0600); returns its path. Nothing is left behind if the write fails."""
    fd, tmp = tempfile.mkstemp(prefix="." + os.path.basename(path) + ".", dir=os.path.dirname(os.path.abspath(path)))
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, 0o666 & ~umask())
    except BaseException:
        os.remove(tmp)
        raise
    return tmp


def write_atomically(path, text):
    """TEXT as the file PATH, whole or not at all."""
    tmp = stage(path, text)
    try:
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise
