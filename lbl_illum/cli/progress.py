"""The command line's progress: a tqdm bar on a terminal, plain lines elsewhere.

The engine reports rays (``update``), the stage (``describe``) and the share of its work
done (``fraction``: the query blocks of each level, :meth:`RunPlan.fraction_done
<lbl_illum.engine.integrator.RunPlan.fraction_done>`).  On a terminal, a bar on standard
error shows the percentage, the time elapsed and left, the stage and the rays (after
one second).  When standard error is not a terminal (a log file, a job scheduler, a
pipe), a plain line every :data:`LINE_SECONDS` says the stage, the percentage and the
time left (once known), the rays so far and the seconds elapsed.  The time left is
elapsed · (1 − f)/f for a share f done: an estimate, as the levels' blocks differ in cost.
"""

from __future__ import annotations

import sys
import time

__all__ = ["ProgressBar", "LINE_SECONDS", "compile_notice"]

#: Seconds between two plain progress lines (standard error not a terminal).
LINE_SECONDS = 5.0
#: What compiling the kernels adds to a first run [s]: the README command on 2 cores, first
#: run against the next (``validation/bench/commands.py``, docs/performance: 17.96 s against
#: 12.88 s; 18.49 against 12.88 in another run; :data:`lbl_illum.engine.compiled.FIRST_RUN`).
COMPILE_SECONDS = 6


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
        self.rays, self.stage, self.done = 0, "", 0.0
        if enabled and not self.plain:
            from tqdm import tqdm

            self.bar = tqdm(total=100, delay=1.0, file=self.stream, leave=False, dynamic_ncols=True,
                            bar_format="{desc} {percentage:3.0f}%|{bar}| {elapsed}<{remaining}{postfix}")

    def update(self, rays: int) -> None:
        if not rays:
            return
        self.rays += rays
        if self.bar is not None:
            self.bar.set_postfix_str(f"{self.rays:,} rays", refresh=False)
            if self.clock() - self.start >= self.bar.delay:      # no bar for a run under a second
                self.bar.refresh()
        elif self.plain:
            self._line()

    def fraction(self, done: float) -> None:
        """The share (0…1) of the work done; it never goes back."""
        done = min(max(float(done), self.done), 1.0)
        if done == self.done:
            return
        if self.bar is not None:
            self.bar.update(100.0 * (done - self.done))
        self.done = done

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
        elapsed = now - self.start
        share = ""
        if self.done > 0.0:
            share = f"{100.0 * self.done:.0f}%, "
            if self.done >= 0.02:
                share += f"about {elapsed * (1.0 - self.done) / self.done:.0f} s left, "
        print(f"{self.label}: {stage}{share}{self.rays:,} rays, {elapsed:.0f} s", file=self.stream, flush=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _is_terminal(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


def compile_notice(enabled: bool, stream=None, bar: ProgressBar | None = None):
    """On the first run after installing, when numba has not compiled the engine's kernels
    yet (:func:`lbl_illum.engine.compiled.kernels_on_disk`), say so before the work starts
    (when ``enabled``).  Returns a context manager for the work: on a first run, while it
    lasts, each kernel numba compiles is named in ``bar`` ("compiling kernels, first run
    only"), so the display does not stand still without saying why; otherwise it does
    nothing."""
    import contextlib

    from ..engine.compiled import kernels_on_disk

    if kernels_on_disk():
        return contextlib.nullcontext()
    if enabled:
        print("lbl-illum: note: compiling the calculation's kernels, first run after installing only "
              f"(about {COMPILE_SECONDS} s more on 2 cores)", file=stream if stream is not None else sys.stderr,
              flush=True)
    if bar is None or not bar.enabled:
        return contextlib.nullcontext()
    from numba.core import event

    return event.install_listener("numba:compile", _compile_listener(bar))


def _compile_listener(bar: ProgressBar):
    """A numba ``numba:compile`` listener naming each outermost compilation in ``bar``."""
    from numba.core import event

    class CompileListener(event.Listener):
        depth = count = 0

        def on_start(self, ev) -> None:
            if self.depth == 0:
                self.count += 1
                bar.describe(f"compiling kernels, first run only ({self.count})")
                if bar.bar is not None and bar.clock() - bar.start >= bar.bar.delay:
                    bar.bar.refresh()
            self.depth += 1

        def on_end(self, ev) -> None:
            self.depth -= 1

    return CompileListener()
