"""What the commands share: argument types for numbers, and the quality options a run
uses, from the scene file, the preset and the command line."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from ..errors import InputError
from ..options import Options

__all__ = ["run_options", "whole", "finite", "check_output_file"]


def whole(minimum: int = 0, maximum: int | None = None):
    """An argparse type: a whole number within [minimum, maximum]."""
    def parse(text):
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"must be >= {minimum}, got {value}")
        if maximum is not None and value > maximum:
            raise argparse.ArgumentTypeError(f"must be <= {maximum}, got {value}")
        return value
    return parse


def finite(minimum: float | None = None, maximum: float | None = None, above: bool = False):
    """An argparse type: a finite number, at least ``minimum`` (greater with ``above``) and
    at most ``maximum``."""
    def parse(text):
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"must be a finite number, got {text!r}")
        if minimum is not None and (value < minimum or (above and value == minimum)):
            raise argparse.ArgumentTypeError(f"must be {'>' if above else '>='} {minimum:g}, got {value:g}")
        if maximum is not None and value > maximum:
            raise argparse.ArgumentTypeError(f"must be <= {maximum:g}, got {value:g}")
        return value
    return parse


def check_output_file(path: str | None, suffix: str | None = None, option: str | None = None) -> None:
    """Refuse, before any work, an output file (``--stats``, ``--cache``, a JSON report)
    whose folder does not exist, that is a folder, or (with ``suffix``) whose name does
    not end in it; ``option`` names the flag in the message."""
    if not path:
        return
    out = Path(path)
    where = f"{option} {path}" if option else str(path)
    if suffix and out.suffix.lower() != suffix:
        raise InputError(f"{where}: the file must end in {suffix}")
    if out.is_dir():
        raise InputError(f"{where}: is a folder; give a file name")
    if not out.resolve().parent.is_dir():
        raise InputError(f"{where}: folder {out.parent} does not exist")


def run_options(scene, args) -> Options:
    """The scene's ``[settings]``, then ``--preset``, then the options given on the command
    line (absent ones, as in a namespace built by hand, count as not given)."""
    def given(name):
        return getattr(args, name, None)

    def metres(name):               # spacings are typed in the scene's units
        value = given(name)
        return None if value is None else value * scene.unit_scale

    options = scene.options.with_preset(given("preset")) if given("preset") else scene.options
    try:
        return options.replace(
            accuracy=given("accuracy"), bounces=given("bounces"), samples=given("samples"), ambient=given("ambient"),
            min_spacing=metres("min_spacing"), max_spacing=metres("max_spacing"), seed=given("seed"),
            interpolation=given("interpolation"), point_samples=given("point_samples"),
            bounce_scaling=False if given("no_bounce_scaling") else None)
    except InputError as exc:   # each value passed its own check: a combination (min > max spacing)
        where = f"the command line with {Path(args.scene).name} [settings]:"
        message = str(exc).replace("options:", where, 1)
        if "spacing" in message:    # its values in the units they were typed in
            lo, hi = (metres(k) or getattr(options, k) for k in ("min_spacing", "max_spacing"))
            message = f"{where} 'min_spacing' ({lo / scene.unit_scale:g}) must not exceed max_spacing " \
                      f"({hi / scene.unit_scale:g})"
        raise InputError(message) from None
