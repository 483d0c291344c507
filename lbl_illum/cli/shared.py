"""What the commands share: the quality options a run uses, from the scene file, the
preset and the command line."""

from __future__ import annotations

from pathlib import Path

from ..errors import InputError
from ..options import Options

__all__ = ["run_options"]


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
