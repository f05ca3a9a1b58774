"""Whether code opens a FIFO for reading, watched from a thread of the test's process (no
child process with a time limit): a writer can open a FIFO without blocking
(``O_WRONLY | O_NONBLOCK``) only while a reader has it open. A reader that blocks in
``open`` is seen at once, and released: the watcher's open and close hand it an empty file."""

from __future__ import annotations

import errno
import os
import threading


class FifoWatch:
    """Watch the FIFO ``path`` inside a ``with`` block; ``opened``: a reader had it open
    meanwhile (polled every 0.2 ms from a thread)."""

    def __init__(self, path):
        self.path, self.opened = os.fspath(path), False
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._watch, daemon=True)

    def __enter__(self):
        self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()

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
