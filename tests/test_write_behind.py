"""The large outputs are written by a second thread (``write_behind.py``): the file holds
exactly the text written, in order; a failure of the thread is raised by the caller's next
write; an output given up midway leaves nothing behind; and a file size limit hit midway is
reported like any other write failure, with the old output kept.  Everything happens in a
temporary folder."""
from __future__ import annotations

import os
import resource
import subprocess
import sys
import textwrap
import threading

import pytest

from mutrose_cp.output import write_behind
from mutrose_cp.output.files import atomic_writer
from mutrose_cp.output.write_behind import WriteBehind


@pytest.fixture
def small_chunks(monkeypatch):
    """Chunks of a few characters, one ahead: every handing over and waiting is exercised."""
    monkeypatch.setattr(write_behind, "CHUNK", 7)
    monkeypatch.setattr(write_behind, "AHEAD", 1)


def test_the_file_holds_the_text_in_order(tmp_path, small_chunks):
    pieces = [f"piece {i} é→{'x' * (i % 13)}\n" for i in range(2000)]
    path = tmp_path / "out.txt"
    fh = WriteBehind(os.open(path, os.O_WRONLY | os.O_CREAT))
    for piece in pieces:
        fh.write(piece)
    fh.flush()
    assert path.read_text(encoding="utf-8") == "".join(pieces)  # all of it, once flushed
    fh.write("end")
    fh.close()
    assert path.read_text(encoding="utf-8") == "".join(pieces) + "end"
    assert fh.closed
    with pytest.raises(OSError):
        os.fstat(fh.fileno())  # the file was closed with the object


def test_a_failure_of_the_thread_is_raised_by_the_next_write(tmp_path, small_chunks):
    """The thread cannot write (the file is open for reading): the caller learns it from a
    write soon after, never waits for the thread, and closing raises it again."""
    path = tmp_path / "out.txt"
    path.write_text("")
    fh = WriteBehind(os.open(path, os.O_RDONLY))
    raised: list[int] = []

    def write_until_it_fails() -> None:
        for i in range(100_000):
            try:
                fh.write("some text ")
            except OSError:
                raised.append(i)
                return

    writer = threading.Thread(target=write_until_it_fails, daemon=True)
    writer.start()
    writer.join(timeout=60)
    assert not writer.is_alive() and raised, "the writes went on (or waited) after the thread failed"
    with pytest.raises(OSError):
        fh.close()
    assert fh.closed


def test_an_output_given_up_midway_leaves_the_old_file(tmp_path, small_chunks):
    out = tmp_path / "decomposition.json"
    out.write_text("previous")
    threads = threading.active_count()
    with pytest.raises(KeyboardInterrupt):
        with atomic_writer(out, behind=True) as fh:
            for _ in range(1000):
                fh.write("{" * 100)
            raise KeyboardInterrupt
    assert out.read_text() == "previous"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["decomposition.json"]
    assert threading.active_count() == threads  # the writing thread has ended


def test_a_file_size_limit_hit_midway_keeps_the_old_output(tmp_path):
    """Twenty megabytes against a one-megabyte limit: the thread's write fails on the first
    chunk, and the failure comes out as the output's error, naming the user's path."""
    out = tmp_path / "out.json"
    out.write_text("previous")
    program = textwrap.dedent(f"""
        from mutrose_cp.errors import MissionError
        from mutrose_cp.output.files import atomic_writer
        try:
            with atomic_writer({str(out)!r}, behind=True) as fh:
                for _ in range(20_000):
                    fh.write("x" * 1000)
        except MissionError as err:
            print(err)
    """)

    def limited() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (1 << 20, 1 << 20))

    result = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, timeout=120,
                            preexec_fn=limited)
    assert result.stdout.strip() == f"{out}: cannot write the output: File too large", result.stderr
    assert out.read_text() == "previous"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.json"]

