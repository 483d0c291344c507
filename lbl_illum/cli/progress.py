"""The command line's progress: a tqdm bar on a terminal, plain lines elsewhere.

On a terminal, a bar on standard error counts rays and names the stage (shown after one
second).  When standard error is not a terminal (a log file, a job scheduler, a pipe),
a plain line every :data:`LINE_SECONDS` says the stage, the rays so far and the seconds
elapsed, so that a long run in a batch job shows it is alive.
"""

from __future__ import annotations

import sys
import time

__all__ = ["ProgressBar", "LINE_SECONDS", "compile_notice"]

#: Seconds between two plain progress lines (standard error not a terminal).
LINE_SECONDS = 5.0


class ProgressBar:
    """Adapter from the engine's progress calls (``update(rays)``, ``describe(text)``)
    to a tqdm bar on a terminal, or plain lines every :data:`LINE_SECONDS` elsewhere;
    ``enabled=False`` shows nothing.  ``stream`` (default standard error) and ``clock``
    (default :func:`time.monotonic`) are for tests."""

    def __init__(self, enabled: bool, stream=None, clock=time.monotonic, label: str = "lbl-illum"):
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = enabled
        self.bar = None
        self.plain = enabled and not _is_terminal(self.stream)
        self.clock, self.label = clock, label
        self.start = self.last = clock()
        self.rays, self.stage = 0, ""
        if enabled and not self.plain:
            from tqdm import tqdm

            self.bar = tqdm(total=None, unit="ray", unit_scale=True, delay=1.0, file=self.stream,
                            leave=False, dynamic_ncols=True)

    def update(self, rays: int) -> None:
        if not rays:
            return
        self.rays += rays
        if self.bar is not None:
            self.bar.update(rays)
        elif self.plain:
            self._line()

    def describe(self, text: str) -> None:
        self.stage = text
        if self.bar is not None:
            self.bar.set_description_str(text, refresh=False)
        elif self.plain:
            self._line()

    def _line(self) -> None:
        now = self.clock()
        if now - self.last < LINE_SECONDS:
            return
        self.last = now
        stage = f"{self.stage}, " if self.stage and self.stage != "done" else ""
        print(f"{self.label}: {stage}{self.rays:,} rays, {now - self.start:.0f} s", file=self.stream, flush=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _is_terminal(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


def compile_notice(enabled: bool, stream=None) -> None:
    """Say, before the work starts, that numba compiles the engine's kernels: the first run
    after installing, which they take most of half a minute of (kept on disk after it;
    :func:`lbl_illum.engine.compiled.kernels_on_disk`)."""
    from ..engine.compiled import kernels_on_disk

    if enabled and not kernels_on_disk():
        print("lbl-illum: note: compiling the calculation's kernels (first run after installing only; "
              "about 15-30 s on 2 cores)", file=stream if stream is not None else sys.stderr, flush=True)
