"""Quality options shared by the Python API, the scene file's ``[settings]`` and the CLI.

=====================  =======  ============================================================
option                 default  meaning
=====================  =======  ============================================================
``accuracy``           0.1      the paper's ``a`` (Eq. 5): a record serves queries whose
                                error estimate is below ``a``.  0 disables interpolation
                                (every query is a primary evaluation: pure Monte Carlo)
``bounces``            8        diffuse reflections followed; 0 = light straight from its
                                source (sun, light surfaces, sky and ground seen directly or
                                through glass).  Radiance's ``-ab`` is ``bounces + 1``
``samples``            1024     hemisphere samples M·N of a primary evaluation (Eq. 2) at the
                                first level of the cache
``ambient``            0        illuminance [lux] substituted at the bounce limit
``min_spacing``        auto     lower clamp on each record's R_i [m] (in ``units`` in a scene
                                file's ``[settings]`` and on the command line: converted there)
``max_spacing``        auto     upper clamp on each record's R_i [m] (the same)
``bounce_scaling``     true     §3.4: each deeper level multiplies ``a`` by 1.4 (up to twice
                                the first level's, and not by growth above 0.4) and halves
                                the samples
``seed``               0        seed of every random number; same seed, same result
``point_samples``      none     every query point gets its own primary evaluation with this
                                many samples (no interpolation among the points), and the
                                cache — ``accuracy``, ``samples`` and §3.4's series — starts at
                                the first reflection.  On sparse sensor grids interpolating
                                among the points buys little.  0 (or none): the cache starts
                                at the points themselves, as in the paper — the choice for
                                dense grids and images
``interpolation``      gradients  ``paper``: Eq. 5 as published; ``gradients``: each record
                                extrapolated by its rotational and translational gradients
                                (Ward & Heckbert 1992) before the Eq. 5 average; ``hessian``:
                                that, with elliptical record domains sized by the irradiance
                                Hessian and leak sectors (Schwarzhaupt et al. 2012)
=====================  =======  ============================================================

**Presets** (``--preset`` on the command line, ``preset = "..."`` under ``[settings]``)
are chosen on part of the accuracy corpus of daylit interiors and reported on the rest
(``lbl-illum validate corpus``; see :data:`PRESETS`); ``lbl-illum validate
office-tradeoff`` places them on the office's speed–accuracy front.  A preset sets
``accuracy``, ``samples``, ``bounces``, ``point_samples`` and ``interpolation``;
options given explicitly win over it.

The defaults in the table are the engine's plain settings, the paper's method (the
cache starts at the query points) with gradients; they are what ``Options()`` holds.  A
*scene* without a preset or options of its own gets :data:`DEFAULT_PRESET` instead
(:func:`scene_defaults`), the most accurate point of the measured front: that is what
``lbl-illum illuminance`` runs when told nothing.

``auto`` spacings are derived from the extent of what is computed (the sensor
points), never from the scene's bounding box: see :func:`lbl_illum.engine.integrator.default_spacing`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Mapping

from .errors import InputError, check_keys

__all__ = ["Options", "PRESETS", "PRESET_MEASURED", "DEFAULT_PRESET", "INTERPOLATIONS", "MAX_BOUNCES", "scene_defaults",
           "BOUNCE_ACCURACY_FACTOR", "BOUNCE_ACCURACY_CAP", "BOUNCE_SAMPLE_FACTOR", "MIN_DEEP_SAMPLES"]

#: §3.4: factor on ``a`` per deeper diffuse level ...
BOUNCE_ACCURACY_FACTOR = 1.4
#: ... up to this multiple of the first level's ``a``.  Unbounded growth reaches a > 1
#: by the seventh level, where Eq. 5 admits records whose normals differ by 90° or more
#: (values the paper calls 100 % wrong); on the office example 8 bounces then gave
#: +14 % bias against a converged reference, and the cap brings 5 bounces to 0.9 %.
BOUNCE_ACCURACY_CAP = 2.0
#: ... and never by growth above this value, the largest a of the paper's own test (§4,
#: Fig. 8).  On the office example a = 0.3 grown to 0.6 at the deeper levels biased the
#: result by +23 % against a converged reference; grown to 0.4, see office-tradeoff.
BOUNCE_ACCURACY_LIMIT = 0.4
#: §3.4: factor on the sample count per deeper diffuse level.
BOUNCE_SAMPLE_FACTOR = 0.5
#: Interpolation rules: the paper's Eq. 5, Eq. 5 over gradient-extrapolated values, and that
#: with Hessian-sized elliptical domains.
INTERPOLATIONS = ("paper", "gradients", "hessian")
#: Most diffuse bounces a scene's ``[settings]``, the command line or ``Options`` may ask
#: for.  The engine keeps bounces + 1 levels of records and a cache file holds at most
#: 1024; the integrating-sphere study converges ρ = 0.9 within 0.5 % in 46 bounces.
MAX_BOUNCES = 1000
#: Floor on the samples of a deeper-level primary evaluation (never above the first level's).
MIN_DEEP_SAMPLES = 16

#: Quality presets, chosen on the accuracy corpus's "choose" scenes (the office, the deep
#: room and the LBNL open-plan office; validation/corpus/README.md) and reported on the
#: held-out ones (docs/validation/corpus/report.md).  Each sets exactly these five options.
#: All evaluate the sensors alone (point samples), cache the reflections with gradients
#: (on the LBNL office the Hessian's domains read +1.3 to +3 % at equal time, gradients
#: within +-0.6 %) and follow 10 bounces: on that bright, cluttered room 8 bounces read
#: -1.05 % against 12, and at 12 the cache's own +0.5 % shows.
PRESETS: dict[str, dict[str, Any]] = {
    "draft": {"accuracy": 0.12, "samples": 64, "bounces": 10, "point_samples": 1024, "interpolation": "gradients"},
    "low": {"accuracy": 0.12, "samples": 128, "bounces": 10, "point_samples": 2048, "interpolation": "gradients"},
    "medium": {"accuracy": 0.1, "samples": 128, "bounces": 10, "point_samples": 4096, "interpolation": "gradients"},
    "high": {"accuracy": 0.08, "samples": 256, "bounces": 10, "point_samples": 8192, "interpolation": "gradients"},
}

#: What each preset measured on examples/office (77 sensors, CIE overcast sky, 2 cores)
#: against the converged reference: (seconds, mean relative error, max relative error).
#: Copied from docs/validation/office-tradeoff/results.json; a test keeps them equal.
PRESET_MEASURED: dict[str, tuple[float, float, float]] = {
    "draft": (1.65, 0.0057, 0.0198),
    "low": (2.97, 0.0057, 0.0180),
    "medium": (4.36, 0.0035, 0.0138),
    "high": (12.41, 0.0031, 0.0131),
}


#: The preset a scene's options start from (see the module docstring).
DEFAULT_PRESET = "high"


def scene_defaults() -> "Options":
    """The options of a scene that sets none: :data:`DEFAULT_PRESET`."""
    return Options().with_preset(DEFAULT_PRESET)


def preset_table() -> str:
    """The presets and what they measured, as the command line's help prints them."""
    lines = ["", "presets (accuracy / samples / bounces; measured on examples/office, 77 sensors, 2 cores, "
             "seconds of calculation without start-up):"]
    for name, p in PRESETS.items():
        text = f"  {name:7s} a {p['accuracy']:g} / {p['samples']} / {p['bounces']}"
        if p["point_samples"]:
            text += f", point samples {p['point_samples']}"
        if all(getattr(Options(), key) == value for key, value in p.items()):
            text += " (the defaults)"
        if name in PRESET_MEASURED:
            sec, mean, worst = PRESET_MEASURED[name]
            text += f": {100 * mean:.1f} % mean, {100 * worst:.1f} % max error, {sec:.1f} s"
        lines.append(text)
    return "\n".join(lines) + "\n"


@dataclass(frozen=True)
class Options:
    """Quality options of an illuminance calculation (see the module table)."""

    accuracy: float = 0.1
    bounces: int = 8
    samples: int = 1024
    ambient: float = 0.0
    min_spacing: float | None = None
    max_spacing: float | None = None
    bounce_scaling: bool = True
    seed: int = 0
    interpolation: str = "gradients"
    point_samples: int | None = None

    def __post_init__(self):
        if self.point_samples == 0 and not isinstance(self.point_samples, bool):
            object.__setattr__(self, "point_samples", None)      # 0: the cache starts at the points
        self.validate("options")

    # -- validation -------------------------------------------------------
    def validate(self, where: str) -> None:
        def bad(key, why):
            raise InputError(f"{where}: '{key}' {why}")

        for key in ("accuracy", "ambient", "min_spacing", "max_spacing"):
            value = getattr(self, key)
            if value is None and key.endswith("spacing"):
                continue
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                bad(key, f"must be a finite number, got {value!r}")
            if value < 0:
                bad(key, f"must be >= 0, got {value!r}")
        if self.point_samples is not None and (isinstance(self.point_samples, bool)
                                               or not isinstance(self.point_samples, int) or self.point_samples < 1):
            bad("point_samples", f"must be a whole number >= 0, got {self.point_samples!r}")
        for key in ("bounces", "samples", "seed"):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, int):
                bad(key, f"must be a whole number, got {value!r}")
        if self.samples < 1:
            bad("samples", f"must be >= 1, got {self.samples}")
        if self.bounces < 0:
            bad("bounces", f"must be >= 0, got {self.bounces}")
        if self.bounces > MAX_BOUNCES:
            bad("bounces", f"must be <= {MAX_BOUNCES}, got {self.bounces}")
        if self.seed < 0:
            bad("seed", f"must be >= 0, got {self.seed}")
        for key in ("min_spacing", "max_spacing"):
            value = getattr(self, key)
            if value is not None and value <= 0:
                bad(key, f"must be > 0, got {value!r}")
        if (self.min_spacing is not None and self.max_spacing is not None
                and self.min_spacing > self.max_spacing):
            bad("min_spacing", f"({self.min_spacing:g}) must not exceed max_spacing ({self.max_spacing:g})")
        if self.interpolation not in INTERPOLATIONS:
            bad("interpolation", f"must be one of {', '.join(INTERPOLATIONS)}, got {self.interpolation!r}")
        if not isinstance(self.bounce_scaling, bool):
            bad("bounce_scaling", f"must be true or false, got {self.bounce_scaling!r}")

    # -- construction -----------------------------------------------------
    @classmethod
    def field_names(cls) -> tuple[str, ...]:
        return tuple(f.name for f in dataclasses.fields(cls))

    @classmethod
    def from_table(cls, table: Mapping[str, Any] | None, where: str, base: "Options | None" = None) -> "Options":
        """Options from a ``[settings]`` table, on top of ``base`` (default: the
        defaults).  A ``preset`` key applies first; the other keys win over it."""
        base = base or cls()
        if not table:
            return base
        check_keys(table, (*cls.field_names(), "preset"), where)
        values = dict(table)
        if "preset" in values:
            base = base.with_preset(values.pop("preset"), where)
        for key in ("accuracy", "ambient", "min_spacing", "max_spacing"):
            if isinstance(values.get(key), int) and not isinstance(values.get(key), bool):
                values[key] = float(values[key])
        try:
            return dataclasses.replace(base, **values)
        except InputError as exc:
            raise InputError(str(exc).replace("options:", f"{where}:", 1)) from None

    def with_preset(self, name: Any, where: str = "options") -> "Options":
        """A copy with the quality options of preset ``name`` (see :data:`PRESETS`)."""
        if not isinstance(name, str) or name not in PRESETS:
            raise InputError(f"{where}: 'preset' must be one of {', '.join(PRESETS)}, got {name!r}")
        return dataclasses.replace(self, **PRESETS[name])

    def replace(self, **changes) -> "Options":
        """A copy with ``changes`` (``None`` values are ignored)."""
        return dataclasses.replace(self, **{k: v for k, v in changes.items() if v is not None})

    # -- §3.4 per-level parameters -----------------------------------------
    def _cache_level(self, level: int) -> int:
        """Position of ``level`` in §3.4's series (it starts one level later with
        ``point_samples``)."""
        return level - 1 if self.point_samples is not None else level

    def level_accuracy(self, level: int) -> float:
        """``a`` at diffuse level ``level`` (0 = the queries themselves)."""
        if self.point_samples is not None and level == 0:
            return 0.0
        if not self.bounce_scaling:
            return self.accuracy
        grown = self.accuracy * min(BOUNCE_ACCURACY_FACTOR ** self._cache_level(level), BOUNCE_ACCURACY_CAP)
        return max(self.accuracy, min(grown, BOUNCE_ACCURACY_LIMIT))

    def level_samples(self, level: int) -> int:
        """Samples of a primary evaluation at diffuse ``level``.

        With accuracy 0 (pure Monte Carlo) the deeper levels follow one path ray per
        hit, so the cost stays samples · (bounces + 1) rays per query.
        """
        if self.point_samples is not None and level == 0:
            return self.point_samples
        level = self._cache_level(level)
        if level == 0:
            return self.samples
        if self.accuracy == 0.0:
            return 1
        if not self.bounce_scaling:
            return self.samples
        scaled = int(round(self.samples * BOUNCE_SAMPLE_FACTOR ** level))
        return max(scaled, min(self.samples, MIN_DEEP_SAMPLES))

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)
