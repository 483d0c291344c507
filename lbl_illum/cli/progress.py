"""The command line's progress bar: a tqdm bar on standard error counting rays."""

from __future__ import annotations

import sys

__all__ = ["ProgressBar"]


class ProgressBar:
    """Adapter from the integrator's progress calls (``update(rays)``, ``describe(text)``)
    to a tqdm bar on standard error, shown after one second and only on a terminal."""

    def __init__(self, enabled: bool):
        from tqdm import tqdm

        self.bar = tqdm(total=None, unit="ray", unit_scale=True, delay=1.0, file=sys.stderr,
                        disable=None if enabled else True, leave=False, dynamic_ncols=True)

    def update(self, rays: int) -> None:
        if rays:
            self.bar.update(rays)

    def describe(self, text: str) -> None:
        self.bar.set_description_str(text, refresh=False)

    def close(self) -> None:
        self.bar.close()
