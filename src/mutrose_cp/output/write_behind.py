"""A text file whose writes reach the disk from a second thread, while the text is still being
formatted.

A large output is gigabytes of text (3.3 GB at 50,000 vital-signs rooms), and the kernel's
share of writing it (copying it into the page cache, and waiting when the disk falls behind)
took three seconds there, every one of them spent waiting by the process that formats it.  The
``write`` system call releases the interpreter's lock, so a thread can make it while the
formatting goes on: :class:`WriteBehind` gathers the text into chunks of eight megabytes,
encodes each and hands it to its thread, at most a few chunks ahead.  The chunks are large
because the thread waits for the interpreter's lock around each ``write`` (up to the switch
interval, 5 ms, while the formatting holds it): with chunks of a megabyte the thread fell
behind and the formatting waited for it instead.

A failure of the thread (a full disk, a file size limit) is raised by the next ``write``,
``flush`` or ``close``, as the file object would have raised it; :meth:`WriteBehind.abandon`
stops the thread without writing what is left, for an output that will be removed.  Only the
thread that made the object may use it, and not across a ``fork`` (the child has no writing
thread).
"""
from __future__ import annotations

import io
import os
import queue
import threading

CHUNK = 1 << 23  # characters gathered before a chunk is handed to the thread
AHEAD = 4  # chunks handed over and not yet written, at most: the memory the thread may hold


class WriteBehind(io.TextIOBase):
    """UTF-8 text written to the open file ``fd``, which it owns and closes."""

    def __init__(self, fd: int) -> None:
        super().__init__()
        self._fd = fd
        self._parts: list[str] = []
        self._size = 0
        self._chunks: queue.Queue[bytes | None] = queue.Queue(maxsize=AHEAD)
        self._error: OSError | None = None
        self._abandoned = False
        self._stopped = False
        self._thread = threading.Thread(target=self._write_chunks, name="output writer", daemon=True)
        self._thread.start()

    def writable(self) -> bool:
        return True

    def fileno(self) -> int:
        return self._fd

    def write(self, s: str) -> int:
        self._parts.append(s)
        self._size += len(s)
        if self._size >= CHUNK:
            self._hand_over()
        return len(s)

    def flush(self) -> None:
        """Wait until everything written so far is in the file; raise the thread's failure."""
        if self._stopped:
            return  # closing: ``close`` has written what there was
        self._hand_over()
        self._chunks.join()
        self._raise_failure()

    def close(self) -> None:
        """Write what is left, stop the thread and close the file; raise the thread's failure."""
        if self.closed:
            return
        try:
            if not self._abandoned:
                self.flush()
        finally:
            self._stop()
            os.close(self._fd)
            super().close()

    def abandon(self) -> None:
        """Stop writing: what is not written yet is dropped, and the file is closed."""
        self._abandoned = True
        self._parts.clear()
        self.close()

    def _hand_over(self) -> None:
        self._raise_failure()
        if self._parts:
            text = "".join(self._parts)
            self._parts.clear()
            self._size = 0
            self._chunks.put(text.encode("utf-8"))

    def _raise_failure(self) -> None:
        if self._error is not None:
            raise self._error

    def _stop(self) -> None:
        """End the thread (it drops what is left once abandoned or failed) and wait for it."""
        self._stopped = True
        self._chunks.put(None)
        self._thread.join()

    def _write_chunks(self) -> None:
        """The thread: write each chunk whole, until the end; after a failure, or once the file
        is abandoned, take the chunks without writing them, so the formatting never waits."""
        while (chunk := self._chunks.get()) is not None:
            try:
                if self._error is None and not self._abandoned:
                    view = memoryview(chunk)
                    while view:
                        view = view[os.write(self._fd, view):]
            except OSError as err:
                self._error = err
            finally:
                self._chunks.task_done()
        self._chunks.task_done()
