"""Whether code opens a FIFO for reading, watched from a thread of the test's process (no
child process with a time limit): a writer can open a FIFO without blocking
(``O_WRONLY | O_NONBLOCK``) only while a reader has it open. A reader that blocks in
``open`` is seen at once, and released: the watcher's open and close hand it an empty file."""

from __future__ import annotations

import contextlib
import errno
import os
import threading


class FifoWatch:
    """``opened``: a reader had ``path`` open while watched (polled every 0.2 ms)."""

    def __init__(self, path):
        self.path, self.opened = os.fspath(path), False
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._watch, daemon=True)

    def _watch(self):
        while not self._stop.is_set():
            try:
                fd = os.open(self.path, os.O_WRONLY | os.O_NONBLOCK)
            except OSError as exc:
                if exc.errno != errno.ENXIO:          # ENXIO: no reader
                    raise
            else:
                self.opened = True
                os.close(fd)
            self._stop.wait(0.0002)


@contextlib.contextmanager
def watched(path):
    """Watch the FIFO ``path`` while the block runs; yields the :class:`FifoWatch`."""
    watch = FifoWatch(path)
    watch._thread.start()
    try:
        yield watch
    finally:
        watch._stop.set()
        watch._thread.join()
