"""The scene: geometry, materials, sky, sun and default settings, read from a TOML scene file.

A scene file (schema 1) has the top-level keys ``schema`` (optional, 1), ``units``
(m, cm, mm, km, ft, in; default m), ``[[geometry]]`` entries, ``[materials.NAME]``
tables, ``[sky]``, ``[sun]``, ``[site]``, ``[[portals]]`` entries, ``[settings]`` and
``[views.NAME]`` tables (named views for ``lbl-illum render``, read by
:func:`lbl_illum.scene.views.views_from_table`; docs/images.md).
A ``[[portals]]`` entry (``vertices = [[x, y, z], ...]``, optional ``name``) is a planar
polygon over an unglazed opening: no ray sees it, and the indirect calculation samples
its area like portal glass (docs/windows.md).  ``[[luminaires]]`` entries place
luminaires from photometric files (:mod:`lbl_illum.scene.luminaires`, docs/luminaires.md).
The daylight tables
(``[sky]``, ``[sun]``, ``[site]``, and a ``weather`` file named in ``[sky]``) are read by
:func:`daylight_from_dict`; docs/daylight.md describes them.  A geometry entry either loads
a file (``file``, relative to the scene file, with a default ``material`` and a ``materials``
table mapping sub-mesh names to materials) or is a primitive (``shape`` = sphere, box,
polygon or rectangle, with a required ``material``).  In a ``materials`` table a
sub-mesh is found by, in this order, its glTF node name, its trimesh geometry name
(OBJ ``GROUP_MATERIAL``, glTF mesh name), its OBJ ``g`` group and its OBJ ``usemtl``
or glTF material name.

Every length of the file, of its geometry files and of ``[settings]``
(``min_spacing``, ``max_spacing``) is in ``units`` and converted to metres.  Every
problem is an :class:`~lbl_illum.errors.InputError` with a one-line message starting
with the scene file's name and the key path (``geometry[2]``, ``[materials.wall]``)
or the line and column.
"""

from __future__ import annotations

import dataclasses
import difflib
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    import tomli as tomllib

from ..errors import InputError, check_keys, get_number, get_vector, plural, show
from ..io.files import read_text_file
from .geometry import (MAX_COORDINATE, Triangles, degenerate_mask, duplicate_mask, load_mesh_file,
                       polygon_triangles, shape_from_table)
from .materials import Material, MaterialTable, material_from_table
from ..options import MAX_BOUNCES, Options, scene_defaults
from ..daylight.sky import (CLEAR_SKY_TYPE, CIEGeneralSky, PerezSky, Sky, gensky_direct_normal, perez_sky_from_weather,
                             sky_from_table)
from ..daylight.solar import day_of_year, read_epw, site_from_table, solar_position, to_utc
from ..daylight.sun import Sun, sun_from_table, sun_position_at
from .luminaires import luminaires_from_table
from .units import metres_per_unit
from .views import views_from_table

__all__ = ["Scene", "load_scene", "scene_from_dict", "daylight_from_dict", "SCHEMA", "TOP_LEVEL_KEYS",
           "MAX_BOUNCES"]

#: The scene-file schema this version reads.
SCHEMA = 1
#: Keys allowed at the top of a scene file.
TOP_LEVEL_KEYS = ("schema", "units", "geometry", "materials", "sky", "sun", "site", "portals", "find_openings",
                  "settings", "views", "luminaires")
#: Keys of a ``[[portals]]`` entry.
PORTAL_KEYS = ("vertices", "name")
#: ``weather_values``: take the weather file's illuminances, or convert its irradiances.
WEATHER_VALUES = ("illuminance", "irradiance")
#: Keys of a ``[[geometry]]`` entry that loads a file.
FILE_KEYS = ("file", "material", "materials")
#: TOML integers are 64-bit (TOML 1.0: "if an integer cannot be represented losslessly, an
#: error must be thrown"); Python's reader accepts larger ones, which are refused here.
_INT64 = (-(2 ** 63), 2 ** 63 - 1)


@dataclass
class Scene:
    """A loaded scene; every length in metres.

    path : the scene file (or None for scenes built in code)
    units : unit of the scene file's lengths; ``unit_scale`` metres per unit
    triangles : all surfaces; ``materials[i]`` is the material of id i
    sky, sun : the daylight (``sun`` None when there is none)
    options : quality options from ``[settings]`` over the ``high`` preset (:func:`~lbl_illum.engine.options.scene_defaults`)
    warnings : things worth telling the user that are not errors
    portals : (k, 3, 3) triangles [m] of the ``[[portals]]`` openings (invisible to rays;
        sampled by the indirect calculation like portal glass)
    views : the ``[views.NAME]`` tables as :class:`~lbl_illum.scene.views.View` s (lengths in metres)
    find_openings : look for unglazed openings in the geometry and sample them as portals
        (:mod:`lbl_illum.engine.openings`; the scene file's ``find_openings``, default true)
    luminaires : the ``[[luminaires]]`` (:class:`~lbl_illum.scene.luminaires.Luminaire`)
    """

    triangles: Triangles
    materials: list[Material]
    sky: Sky
    sun: Sun | None = None
    options: Options = field(default_factory=scene_defaults)
    units: str = "m"
    unit_scale: float = 1.0
    path: Path | None = None
    warnings: list[str] = field(default_factory=list)
    portals: np.ndarray = field(default_factory=lambda: np.zeros((0, 3, 3)))
    views: dict = field(default_factory=dict)
    find_openings: bool = True
    luminaires: list = field(default_factory=list)

    @property
    def material_table(self) -> MaterialTable:
        return MaterialTable.from_materials(self.materials)


# ---------------------------------------------------------------------------
# Reading a scene file
# ---------------------------------------------------------------------------

def load_scene(path: str | Path) -> Scene:
    """Read a TOML scene file (schema 1); every length of the result is in metres.

    Geometry files are found relative to the scene file.  Every problem is an
    :class:`InputError` whose one-line message starts with the file's name.
    """
    path = Path(path)
    name = path.name or str(path)
    text = read_text_file(path, " scene")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(_toml_error(name, exc)) from None
    except RecursionError:          # thousands of nested arrays
        raise InputError(f"{name}: values nested too deeply") from None
    except ValueError:              # Python's limit on the digits of an integer (4300)
        raise InputError(f"{name}: an integer is too long to read (TOML integers are 64-bit)") from None
    _check_integers(data, name, "")
    scene = scene_from_dict(data, path.parent, name)
    scene.path = path
    return scene


def _check_integers(value: Any, name: str, key: str) -> None:
    """Refuse integers outside the 64-bit range of TOML, naming the key."""
    stack = [(value, key)]
    while stack:
        item, path = stack.pop()
        if isinstance(item, dict):
            stack.extend((v, f"{path}.{k}" if path else str(k)) for k, v in item.items())
        elif isinstance(item, list):
            stack.extend((v, f"{path}[{i}]") for i, v in enumerate(item))
        elif isinstance(item, int) and not isinstance(item, bool) and not _INT64[0] <= item <= _INT64[1]:
            raise InputError(f"{name}: '{path}': integer of {item.bit_length()} bits is beyond TOML's "
                             "64-bit range")


def _toml_error(name: str, exc: Exception) -> str:
    """``scene.toml: line L, column C: message`` from a TOML syntax error."""
    message = str(exc).splitlines()[0] if str(exc) else "invalid TOML"
    found = re.search(r"^(.*?)\s*\(at line (\d+), column (\d+)\)$", message)
    if found:
        return f"{name}: line {found[2]}, column {found[3]}: {found[1]}"
    found = re.search(r"^(.*?)\s*\(at end of document\)$", message)
    if found:
        return f"{name}: end of file: {found[1]}"
    return f"{name}: {message}"


def scene_from_dict(data: Mapping[str, Any], base_dir: str | Path, where: str) -> Scene:
    """Build a :class:`Scene` from a parsed scene file (a plain dict).

    ``base_dir`` is where geometry files are looked up; ``where`` names the source in
    messages (normally the scene file's name).  Lengths are in ``data["units"]`` and
    come out in metres, the ``[settings]`` spacings too.
    """
    if not isinstance(data, Mapping):
        raise InputError(f"{where}: a scene must be a table of keys, got {type(data).__name__}")
    check_keys(data, TOP_LEVEL_KEYS, where)
    _check_schema(data, where)
    units = data.get("units", "m")
    scale = metres_per_unit(units, f"{where}: 'units'")
    material_warnings: list[str] = []
    materials = _materials(_table(data, "materials", where, "[materials]"), where, material_warnings)
    sun, sky, warnings = daylight_from_dict(data, base_dir, where)
    warnings = material_warnings + warnings
    options = _options(_table(data, "settings", where, "[settings]"), f"{where}: [settings]", scale)
    models: list = []                  # Honeybee models: their views and notes join the scene's
    primitives: list = []              # every Radiance primitive read: a sky and sun they describe
    triangles = _geometry(data.get("geometry"), where, Path(base_dir), scale, materials, warnings, units, models,
                          primitives)
    if "sky" not in data and "sun" not in data and primitives:
        from .radsky import radiance_daylight

        found = radiance_daylight(primitives, where)
        if found is not None:
            sky = found[0] if found[0] is not None else sky
            sun = found[1]
            warnings.append(f"{where}: no [sky] or [sun]: {found[2]} of the Radiance files is used")
    used = set(np.unique(triangles.material).tolist())
    warnings += [f"{where}: [materials.{m.name}] is not used by any geometry"
                 for i, m in enumerate(materials) if i not in used]
    portals = _portals(data.get("portals"), where, scale)
    triangles, portals = _opening_faces(triangles, materials, portals, where)
    find_openings = data.get("find_openings", True)
    if not isinstance(find_openings, bool):
        raise InputError(f"{where}: 'find_openings' must be true or false, got {show(find_openings)}")
    views = _no_overflow(lambda: views_from_table(data.get("views"), where, scale), f"{where}: [views]",
                         "the views")
    for model in models:
        warnings += model.warnings
        for name, view in model.views.items():
            views.setdefault(name, view)
    luminaires = luminaires_from_table(data.get("luminaires"), where, base_dir, scale)
    photometries = {id(lum.photometry): lum.photometry for lum in luminaires}
    warnings += [note for photometry in photometries.values() for note in photometry.notes]
    return Scene(triangles=triangles, materials=materials, sky=sky, sun=sun, options=options,
                 units=units, unit_scale=scale, warnings=warnings, portals=portals, views=views,
                 find_openings=find_openings, luminaires=luminaires)


def _opening_faces(triangles: Triangles, materials: list[Material], portals: np.ndarray, where: str):
    """Faces of the ``opening`` material: taken out of the traced geometry and added to the
    portals (unglazed openings, sampled by area and seen by no ray)."""
    opening = np.array([m.kind == "opening" for m in materials], bool)
    if not opening.any():
        return triangles, portals
    mask = opening[triangles.material]
    if mask.all():
        raise InputError(f"{where}: every surface has an 'opening' material: nothing is left to light")
    kept = Triangles(triangles.vertices[~mask], triangles.material[~mask], triangles.sphere[~mask],
                     triangles.sphere_center, triangles.sphere_radius)
    return kept, np.concatenate([portals, triangles.vertices[mask]])


def _portals(entries: Any, where: str, scale: float) -> np.ndarray:
    """(k, 3, 3) triangles [m] of the ``[[portals]]`` polygons, each checked (at least
    three vertices, planar, non-zero area, edges not crossing) and triangulated."""
    if entries is None:
        return np.zeros((0, 3, 3))
    if not isinstance(entries, (list, tuple)):
        raise InputError(f"{where}: 'portals' must be an array of tables ([[portals]]), got {show(entries)}")
    out = []
    for i, entry in enumerate(entries):
        label = f"{where}: portals[{i}]"
        if not isinstance(entry, Mapping):
            raise InputError(f"{label}: must be a table with 'vertices', got {show(entry)}")
        check_keys(entry, PORTAL_KEYS, label, required=("vertices",))
        if "name" in entry and not isinstance(entry["name"], str):
            raise InputError(f"{label}: 'name' must be a string, got {show(entry['name'])}")
        value = entry["vertices"]
        if not isinstance(value, (list, tuple)):
            raise InputError(f"{label}: 'vertices' must be a list of [x, y, z] points, got {show(value)}")
        points = np.array([get_vector({f"vertices[{j}]": p}, f"vertices[{j}]", label) for j, p in enumerate(value)],
                          dtype=np.float64).reshape(-1, 3)
        out.append(polygon_triangles(points * scale, f"{label} 'vertices'"))
    return np.concatenate(out) if out else np.zeros((0, 3, 3))


# ---------------------------------------------------------------------------
# Daylight: [sky], [sun], [site] and weather files
# ---------------------------------------------------------------------------

def daylight_from_dict(data: Mapping[str, Any], base_dir: str | Path, where: str
                       ) -> tuple[Sun | None, Sky, list[str]]:
    """The sun, the sky and warnings of a parsed scene file's ``[sky]``, ``[sun]`` and ``[site]``.

    The sun that shapes a sky (CIE general, Perez) is positioned, in this order, by
    ``[sun] altitude, azimuth``, by ``[sun] time`` or by ``[sky] time`` at the ``[site]``,
    or by the ``[sky] time`` of a ``[sky] weather`` file at the file's site.  A sky
    positioned by ``[sky] time`` without a ``[sun]`` table gets a sun with
    ``direct_normal_illuminance = 0`` (it positions, but adds no light), except a Perez
    sky, whose sun carries the sky's own direct normal illuminance.  ``weather`` is
    relative to ``base_dir``.
    """
    sky_table = _table(data, "sky", where, "[sky]")
    sun_table = _table(data, "sun", where, "[sun]")
    site_table = _table(data, "site", where, "[site]")
    sky_where, sun_where, site_where = f"{where}: [sky]", f"{where}: [sun]", f"{where}: [site]"
    warnings: list[str] = []
    if sky_table is not None and "weather" in sky_table:
        return _weather_daylight(sky_table, sun_table, site_table, Path(base_dir), where, warnings)
    if sky_table is not None and "weather_values" in sky_table:
        raise InputError(f"{sky_where}: 'weather_values' goes with a 'weather' file")
    site = None
    if site_table is not None:
        site = site_from_table(site_table, site_where)
        if (w := site.meridian_warning(site_where)) is not None:
            warnings.append(w)
    sky_time = sky_table.get("time") if sky_table is not None else None
    if sky_time is not None and sun_table is not None:
        raise InputError(f"{sky_where}: 'time' and a [sun] table both position the sun: give the time in one of them")
    if site is not None and sky_time is None and (sun_table is None or "time" not in sun_table):
        warnings.append(f"{site_where}: not used (no 'time' in [sun] or [sky])")
    position, day, utc = None, None, None
    # the sun's position first: a Perez sky's direct normal value is the [sun]'s default
    if sun_table is not None:
        probe = sun_from_table(sun_table, sun_where, site, default_direct_normal=0.0, site_where="[site]")
        position, utc = (probe.altitude, probe.azimuth), probe.time
    elif sky_time is not None:
        alt, az, utc = sun_position_at(sky_time, site, sky_where)
        position = (alt, az)
    if utc is not None:
        day = day_of_year(utc)
    sky = _sky(sky_table, sky_where, position, day)
    if sun_table is not None:
        default = sky.direct_normal_illuminance if isinstance(sky, PerezSky) else None
        if isinstance(sky, CIEGeneralSky) and sky.sky_type == CLEAR_SKY_TYPE and position is not None:
            default = gensky_direct_normal(position[0])      # beside a clear sky, gensky's sun
        sun = sun_from_table(sun_table, sun_where, site, default_direct_normal=default, site_where="[site]")
        if isinstance(sky, PerezSky) and "direct_normal_illuminance" in sun_table and \
                sun.direct_normal_illuminance not in (0.0, sky.direct_normal_illuminance):
            warnings.append(f"{sun_where}: direct_normal_illuminance {sun.direct_normal_illuminance:g} lux differs "
                            f"from the Perez sky's {sky.direct_normal_illuminance:.6g} lux")
    elif position is not None:
        edn = sky.direct_normal_illuminance if isinstance(sky, PerezSky) else 0.0
        sun = Sun(position[0], position[1] % 360.0, edn, time=utc)
        if edn > 0.0 and position[0] <= 0.0:
            sun = dataclasses.replace(sun, warnings=(f"{sky_where}: the sun is below the horizon (altitude "
                                                      f"{position[0]:.4g}°): no direct sun",))
    else:
        sun = None
    warnings += _sky_warnings(sky, sky_where)
    if sun is not None:
        warnings += list(sun.warnings)
        if sun.horizontal_illuminance > 0.0:
            sky = dataclasses.replace(sky, sun_horizontal_illuminance=float(sun.horizontal_illuminance))
    return sun, sky, warnings


def _sky(table: Mapping[str, Any] | None, where: str, position, day) -> Sky:
    """:func:`~lbl_illum.daylight.sky.sky_from_table`, with two guards: ``sky_type`` must be a finite
    number before the sky reads it as a whole number, and a value so large that the sky
    model overflows (a Perez sky of 1e308 lux) is refused, naming the table."""
    if table is not None and isinstance(table.get("sky_type"), float) and not np.isfinite(table["sky_type"]):
        raise InputError(f"{where}: 'sky_type' must be a whole number 1…15, got {table['sky_type']!r}")
    return _no_overflow(lambda: sky_from_table(table, where, sun_position=position, day=day, extra_keys=("time",)),
                        where, "the sky model")


def _no_overflow(build, where: str, what: str):
    """``build()``, with a floating-point overflow (a value such as 1e300 that passed the
    table's own checks) refused as an :class:`InputError` naming ``where``."""
    try:
        with np.errstate(over="raise"):
            return build()
    except (OverflowError, FloatingPointError):
        raise InputError(f"{where}: a value is too large for {what} (overflow)") from None


def _sky_warnings(sky: Sky, where: str) -> list[str]:
    if isinstance(sky, CIEGeneralSky) and sky.sun_altitude is not None and sky.sun_altitude < 0.0 \
            and sky.sky_type not in (1, 3, 5):
        return [f"{where}: the sun is below the horizon (altitude {sky.sun_altitude:.4g}°): the CIE general "
                "sky is defined for a sun above it"]
    if isinstance(sky, PerezSky) and sky.sun_altitude <= 0.0 and sky.horizontal_illuminance > 0.0:
        return [f"{where}: the sun is below the horizon (altitude {sky.sun_altitude:.4g}°): the Perez sky "
                "takes it at the horizon"]
    return []


def _weather_daylight(sky_table, sun_table, site_table, base_dir: Path, where: str, warnings: list[str]):
    """``[sky] weather = "file.epw", time = "MM-DD HH:MM"``: a Perez sky and sun for one hour."""
    sky_where = f"{where}: [sky]"
    check_keys(sky_table, ("type", "weather", "time", "weather_values", "ground_reflectance"), sky_where,
               required=("time",))
    kind = sky_table.get("type", "perez")
    if kind != "perez":
        raise InputError(f"{sky_where}: a 'weather' file gives a Perez sky: 'type' must be \"perez\" (or left out), "
                         f"got {show(kind)}")
    if site_table is not None:
        raise InputError(f"{where}: [site] is not used with a weather file (the site is the file's LOCATION line)")
    if sun_table is not None:
        raise InputError(f"{where}: [sun] is not used with a weather file (the sun is the file's)")
    file = sky_table["weather"]
    if not isinstance(file, str) or not file:
        raise InputError(f"{sky_where}: 'weather' must be a file name, got {show(file)}")
    values = sky_table.get("weather_values", "illuminance")
    if values not in WEATHER_VALUES:
        raise InputError(f"{sky_where}: 'weather_values' must be one of {', '.join(WEATHER_VALUES)}, got {show(values)}")
    rho = get_number(sky_table, "ground_reflectance", sky_where, default=0.2, minimum=0.0, maximum=1.0)
    epw = read_epw(base_dir / file, f"{where}: [sky] weather {file}")
    rec, local = epw.record_at(sky_table["time"], f"{sky_where} (weather {file})")
    utc = to_utc(local, epw.site.time_zone)
    pos = solar_position(utc, epw.site.latitude, epw.site.longitude, epw.site.elevation)
    alt, az = float(pos.altitude), float(pos.azimuth) % 360.0
    label = f"{where}: [sky] weather {file}: line {rec.line}"
    try:
        sky = perez_sky_from_weather(rec.direct_normal_irradiance, rec.diffuse_horizontal_irradiance,
                                     rec.direct_normal_illuminance, rec.diffuse_horizontal_illuminance, (alt, az),
                                     day=day_of_year(utc), dew_point=rec.dew_point,
                                     use_file_illuminance=values == "illuminance", ground_reflectance=rho)
    except ValueError as exc:
        raise InputError(f"{label}: {exc}") from None
    sun = Sun(alt, az, sky.direct_normal_illuminance, time=utc)
    warnings += _sky_warnings(sky, sky_where)
    if sun.direct_normal_illuminance > 0.0 and alt <= 0.0:
        warnings.append(f"{label}: the sun is below the horizon (altitude {alt:.4g}°): no direct sun")
    if sun.horizontal_illuminance > 0.0:
        sky = dataclasses.replace(sky, sun_horizontal_illuminance=float(sun.horizontal_illuminance))
    return sun, sky, warnings


def _check_schema(data: Mapping[str, Any], where: str) -> None:
    schema = data.get("schema", SCHEMA)
    if isinstance(schema, bool) or schema != SCHEMA:
        raise InputError(f"{where}: 'schema' {show(schema)} is not supported (this version reads schema {SCHEMA})")


def _table(data: Mapping[str, Any], key: str, where: str, label: str) -> Mapping[str, Any] | None:
    """``data[key]`` when it is a table, None when absent; anything else is an error."""
    value = data.get(key)
    if value is not None and not isinstance(value, Mapping):
        raise InputError(f"{where}: {label} must be a table, got {show(value)}")
    return value


#: Radiance's reference manual ("Plastic"): specularity fractions above 0.1 and roughness
#: values above 0.2 are not very realistic; a plastic beyond either gets a warning.
PLASTIC_REALISTIC = (0.1, 0.2)


def _materials(table: Mapping[str, Any] | None, where: str, warnings: list[str]) -> list[Material]:
    """All ``[materials.NAME]`` tables in file order (index = material id).

    A reflectance of exactly 1 (diffuse or mirror) is accepted with a warning: such a
    surface absorbs nothing, so the interreflections in a closed room form a series that
    does not converge; every run stops it at a finite depth (``bounces`` diffuse levels,
    at most :data:`MAX_BOUNCES`, and :data:`lbl_illum.engine.paths.MAX_SPECULAR_DEPTH` specular
    interactions), so the result is finite but grows with ``bounces``.  A plastic with
    specularity above 0.1 or roughness above 0.2 (:data:`PLASTIC_REALISTIC`) is accepted
    with a warning too.
    """
    materials = []
    for name, entry in (table or {}).items():
        label = f"{where}: [materials.{name}]"
        if not isinstance(entry, Mapping):
            raise InputError(f"{label} must be a table, got {show(entry)}")
        material = material_from_table(name, entry, label)
        if material.kind in ("diffuse", "mirror") and max(material.reflectance) >= 1.0:
            warnings.append(f"{label}: reflectance 1 absorbs no light; interreflections are summed up to the "
                            "bounce limit only, and the result grows with 'bounces'")
        if material.kind == "plastic" and (material.specularity > PLASTIC_REALISTIC[0]
                                           or material.roughness > PLASTIC_REALISTIC[1]):
            warnings.append(f"{label}: specularity above {PLASTIC_REALISTIC[0]:g} or roughness above "
                            f"{PLASTIC_REALISTIC[1]:g} is not very realistic for plastic (Radiance reference "
                            "manual); a metal or a coated surface needs another material")
        materials.append(material)
    return materials


def _options(table: Mapping[str, Any] | None, where: str, scale: float) -> Options:
    """``[settings]``.  Spacings are given in scene units and converted to metres (the
    engine takes metres only).  ``bounces`` is at most :data:`MAX_BOUNCES`."""
    if table is not None and "preset" in table and not isinstance(table["preset"], str):
        raise InputError(f"{where}: 'preset' must be a name (a string), got {show(table['preset'])}")
    options = Options.from_table(table, where, base=scene_defaults())
    if options.bounces > MAX_BOUNCES:
        raise InputError(f"{where}: 'bounces' must be <= {MAX_BOUNCES}, got {options.bounces}")
    return in_metres(options, scale)


def in_metres(options: Options, scale: float) -> Options:
    """``options`` with spacings given in scene units (``scale`` metres each) in metres."""
    return options.replace(**{key: getattr(options, key) * scale for key in ("min_spacing", "max_spacing")
                              if getattr(options, key) is not None})


# ---------------------------------------------------------------------------
# Geometry
# ---------------------------------------------------------------------------

@dataclass
class _Chunk:
    """Triangles of one ``[[geometry]]`` entry [m], with material and sphere ids."""

    label: str
    vertices: np.ndarray
    material: np.ndarray
    sphere: np.ndarray


def _geometry(entries: Any, where: str, base_dir: Path, scale: float, materials: list[Material],
              warnings: list[str], units: str = "m", models: list | None = None,
              primitives: list | None = None) -> Triangles:
    """All triangles of the ``[[geometry]]`` entries, cleaned (see :func:`_assemble`).

    Radiance files (``.rad``, ``.mat``) are read first, all of them, for their modifier
    definitions: a modifier that no ``materials`` mapping and no ``[materials]`` table of
    the same name gives a material becomes one (:func:`_radiance_materials`), appended to
    ``materials``."""
    if entries is None:
        raise InputError(f"{where}: the scene has no geometry (add [[geometry]] entries)")
    if not isinstance(entries, (list, tuple)):
        raise InputError(f"{where}: 'geometry' must be an array of tables ([[geometry]]), got {show(entries)}")
    ids = {m.name: i for i, m in enumerate(materials)}
    radiance, reads = _radiance_files(entries, where, base_dir, units, models, scale)
    if primitives is not None:
        primitives += [p for prims, _ in radiance.values() for p in prims]
    # the modifiers of all the scene's Radiance files: name → (primitive, where it was read)
    definitions = {}
    if radiance:                                       # the radfile module only for Radiance files
        from .radfile import modifier_definitions

        definitions = {name: (p, w) for prims, w in radiance.values() for name, p in modifier_definitions(prims).items()}
    chunks, centers, radii = [], [], []
    for i, entry in enumerate(entries):
        label = f"{where}: geometry[{i}]"
        if not isinstance(entry, Mapping):
            raise InputError(f"{label}: must be a table, got {show(entry)}")
        if "file" in entry and "shape" in entry:
            raise InputError(f"{label}: give either 'file' or 'shape', not both")
        if i in radiance:
            chunk = _radiance_chunk(entry, label, scale, ids, materials, radiance, i, warnings, definitions, reads.get(i))
            if chunk is not None:
                chunks.append(chunk)
        elif "file" in entry:
            chunks.append(_file_chunk(entry, label, base_dir, scale, ids, warnings, materials, definitions))
        elif "shape" in entry:
            chunk, shape = _shape_chunk(entry, label, scale, ids, len(centers))
            chunks.append(chunk)
            if shape.sphere_center is not None:
                centers.append(shape.sphere_center)
                radii.append(shape.sphere_radius)
        else:
            raise InputError(f"{label}: needs 'file' (a geometry file) or 'shape' "
                             "(sphere, box, polygon, rectangle)")
    triangles = _assemble(chunks, warnings)
    if len(triangles) == 0:
        raise InputError(f"{where}: the scene has no triangles")
    triangles.sphere_center = np.array(centers, dtype=np.float64).reshape(-1, 3)
    triangles.sphere_radius = np.array(radii, dtype=np.float64)
    return triangles


#: Suffixes of Radiance scene files, read by :mod:`lbl_illum.scene.radfile`.
RADIANCE_SUFFIXES = (".rad", ".mat")


@dataclass
class _RadianceRead:
    """How a Radiance file was read: its geometry-cache key, the files its reading read
    (None: it came from the cache) and, from the cache, ``(parts, warnings)`` of its
    surfaces."""

    key: str | None
    reads: list | None = None
    surfaces: tuple | None = None


def _radiance_files(entries, where: str, base_dir: Path, units: str = "m", models: list | None = None,
                    scale: float = 1.0) -> tuple[dict, dict]:
    """``({entry index: (primitives, label)}, {entry index: _RadianceRead})``: the entries
    that name Radiance files or Honeybee models (those appended to ``models``: their views
    and warnings), and how each Radiance file was read.  A Radiance file read before at
    ``scale``, with every file it read unchanged, comes from the geometry cache
    (:func:`lbl_illum.scene.geometry_cache.load_radiance`: its primitives other than
    surfaces, and its surfaces)."""
    from .honeybee import HONEYBEE_SUFFIXES, read_honeybee

    models = [] if models is None else models

    out, how = {}, {}
    for i, entry in enumerate(entries):
        if isinstance(entry, Mapping) and isinstance(entry.get("file"), str) and "shape" not in entry \
                and Path(entry["file"]).suffix.lower() in RADIANCE_SUFFIXES + HONEYBEE_SUFFIXES:
            label = f"{where}: geometry[{i}]"
            check_keys(entry, FILE_KEYS, label)
            label = f"{label} {entry['file']}"
            if Path(entry["file"]).suffix.lower() in HONEYBEE_SUFFIXES:
                model = read_honeybee(base_dir / entry["file"], label, units)
                out[i] = (model.primitives, label)
                models.append(model)
            else:
                from . import geometry_cache
                from .radfile import files_read, read_rad          # imported only for Radiance files

                path = base_dir / entry["file"]
                key = geometry_cache.radiance_key(path, label, scale) if path.is_file() else None
                found = geometry_cache.load_radiance(key)
                if found is not None:
                    out[i] = (found[0], label)
                    how[i] = _RadianceRead(key, None, found[1:])
                else:
                    with files_read() as reads:
                        out[i] = (read_rad(path, label), label)
                    how[i] = _RadianceRead(key, reads)
    return out, how


def _radiance_chunk(entry, label: str, scale: float, ids: dict[str, int], materials: list[Material],
                    radiance: dict, index: int, warnings: list[str], definitions: dict,
                    read: _RadianceRead | None = None) -> _Chunk | None:
    """A Radiance-file entry: its surfaces by modifier, each modifier's material the one
    its ``materials`` mapping names, else the ``[materials]`` table of its name, else its
    own definition in the scene's Radiance files (made a material here), else the entry's
    default ``material``.  A ``.mat`` file (definitions only) gives no chunk.

    ``definitions``: the modifiers of all the scene's Radiance files (name → (primitive,
    where it was read)); ``read``: how the file was read (:class:`_RadianceRead`), its
    surfaces when they came from the geometry cache, which they go to otherwise."""
    from .radfile import SURFACE_TYPES, MESH_TRIANGLES, material_name, rad_surfaces

    prims, where = radiance[index]
    default = _material_id(entry["material"], label, ids) if "material" in entry else None
    mapping = entry.get("materials", {})
    if not isinstance(mapping, Mapping):
        raise InputError(f"{label}: 'materials' must be a table of name = material, got {show(mapping)}")
    mapped = {key: _material_id(value, f"{label}: materials.{key}", ids) for key, value in mapping.items()}
    if read is not None and read.surfaces is not None:
        parts, notes = read.surfaces
    else:
        notes = []
        parts = rad_surfaces(prims, where, scale, notes)
        if parts and read is not None:
            from .geometry_cache import store_radiance

            store_radiance(read.key, read.reads, [p for p in prims if p.kind not in SURFACE_TYPES
                                                  and p.kind != MESH_TRIANGLES], parts, notes)
    warnings.extend(notes)
    if not parts:
        if Path(entry["file"]).suffix.lower() == ".mat" or any(p.kind != "polygon" for p in prims):
            return None
        raise InputError(f"{where}: the file contains no surfaces")
    # a part is named by its surfaces' modifier; patterns and aliases lead to a material
    for part in parts:
        part.material = material_name(part.name, definitions)
    missing = list(dict.fromkeys(p.material for p in parts if not any(k in mapped or k in ids for k in p.keys)
                                 and (default is None or p.material in definitions)))
    if missing:
        _radiance_materials(missing, definitions, where, ids, materials, warnings)
    vertices, material = [], []
    for part in parts:
        key = next((k for k in part.keys if k in mapped), None)
        mid = mapped[key] if key is not None else next((ids[k] for k in part.keys if k in ids), default)
        vertices.append(part.vertices)
        material.append(np.full(len(part.vertices), mid, dtype=np.int32))
    _check_mapping_used(mapped, {k for p in parts for k in p.keys}, parts, where)
    v = np.concatenate(vertices)
    return _Chunk(where, v, np.concatenate(material), np.full(len(v), -1, dtype=np.int32))


def _radiance_materials(names: list[str], definitions: dict, where: str, ids: dict[str, int],
                        materials: list[Material], warnings: list[str]) -> None:
    """Materials for the Radiance modifiers ``names`` from their definitions
    (:func:`lbl_illum.scene.radfile.material_tables`), appended to ``materials`` and ``ids``."""
    from .radfile import material_tables

    try:
        tables = material_tables(definitions, names, warnings)
    except InputError as exc:
        raise InputError(f"{where}: {exc}" if not str(exc).startswith(where.split(":")[0]) else str(exc)) from None
    for name, table in tables.items():
        label = f"{where}: modifier '{name}'"
        ids[name] = len(materials)
        materials.append(material_from_table(name, table, label))


def _material_id(name: Any, label: str, ids: dict[str, int]) -> int:
    """Id of a defined material; unknown names are an error with a suggestion."""
    if not isinstance(name, str):
        raise InputError(f"{label}: a material must be given by its name (a string), got {show(name)}")
    if name not in ids:
        near = difflib.get_close_matches(name, list(ids), n=1)
        hint = f" (did you mean '{near[0]}'?)" if near else (
            " (no [materials] are defined)" if not ids else f" (defined: {', '.join(ids)})")
        raise InputError(f"{label}: unknown material '{name}'{hint}")
    return ids[name]


def _own_name_material(part, label: str, ids: dict[str, int], materials: list[Material] | None,
                       definitions: dict, warnings: list[str]) -> int | None:
    """Id of the material named like one of the sub-mesh's names (``part.keys``, most
    specific first): a material already defined, else a Radiance modifier of that name
    in ``definitions`` (made a material).  None when no name has one."""
    key = next((k for k in part.keys if k in ids), None)
    if key is not None:
        return ids[key]
    key = next((k for k in part.keys if k in definitions), None)
    if key is None or materials is None:
        return None
    from .radfile import material_name

    name = material_name(key, definitions)
    if name not in ids:
        _radiance_materials([name], definitions, label, ids, materials, warnings)
    ids[key] = ids[name]
    return ids[key]


def _shape_chunk(entry: Mapping[str, Any], label: str, scale: float, ids: dict[str, int], sphere_index: int):
    """A primitive entry (``shape = ...``) as a chunk and its :class:`~lbl_illum.scene.geometry.Shape`."""
    shape = shape_from_table(entry, label, scale, extra_keys=("material",))
    if "material" not in entry:
        raise InputError(f"{label}: missing key 'material'")
    n = len(shape.vertices)
    material = np.full(n, _material_id(entry["material"], label, ids), dtype=np.int32)
    sphere = np.full(n, sphere_index if shape.sphere_center is not None else -1, dtype=np.int32)
    return _Chunk(label, shape.vertices, material, sphere), shape


def _file_chunk(entry: Mapping[str, Any], label: str, base_dir: Path, scale: float,
                ids: dict[str, int], warnings: list[str], materials: list[Material] | None = None,
                definitions: dict | None = None) -> _Chunk:
    """A geometry-file entry: every sub-mesh gets its mapped material or the default.
    Without either, a sub-mesh takes the material of its own name (its names in the order
    of the mapping), a ``[materials]`` table or, as Radiance's ``obj2rad`` and ``mesh``
    make a ``usemtl`` name a modifier, a modifier defined in the scene's Radiance files
    (``definitions``: name → (primitive, where it was read); made a material and appended to
    ``materials``).  Faces triangulated with a mismatch of areas are reported in
    ``warnings``."""
    check_keys(entry, FILE_KEYS, label)
    file = entry["file"]
    if not isinstance(file, str) or not file:
        raise InputError(f"{label}: 'file' must be a file name, got {show(file)}")
    default = _material_id(entry["material"], label, ids) if "material" in entry else None
    mapping = entry.get("materials", {})
    if not isinstance(mapping, Mapping):
        raise InputError(f"{label}: 'materials' must be a table of name = material, got {show(mapping)}")
    mapped = {key: _material_id(value, f"{label}: materials.{key}", ids) for key, value in mapping.items()}
    label = f"{label} {file}"
    parts = load_mesh_file(base_dir / file, label, scale, warnings)
    definitions = definitions or {}
    vertices, material, matched = [], [], set()
    for part in parts:
        key = next((k for k in part.keys if k in mapped), None)
        mid = default if key is None else mapped[key]
        if mid is None:
            mid = _own_name_material(part, label, ids, materials, definitions, warnings)
        if mid is None:
            raise InputError(f"{label}: no material for sub-mesh {part.label}: map it in 'materials', "
                             "give a default 'material', or define a material of its name")
        matched.add(key)
        vertices.append(part.vertices)
        material.append(np.full(len(part.vertices), mid, dtype=np.int32))
    _check_mapping_used(mapped, matched, parts, label)
    v = np.concatenate(vertices)
    return _Chunk(label, v, np.concatenate(material), np.full(len(v), -1, dtype=np.int32))


def _check_mapping_used(mapped: dict[str, int], matched: set, parts: list, label: str) -> None:
    """A ``materials`` key naming no sub-mesh is a typo: refuse it, suggesting the names found."""
    names = list(dict.fromkeys(k for part in parts for k in part.keys))
    for key in mapped:
        if key not in matched:
            near = difflib.get_close_matches(key, names, n=1)
            hint = f"did you mean '{near[0]}'?" if near else (
                f"names in the file: {', '.join(names)}" if names else "the file has no names")
            raise InputError(f"{label}: 'materials' key '{key}' names no material, group or mesh "
                             f"of the file ({hint})")


def _assemble(chunks: list[_Chunk], warnings: list[str]) -> Triangles:
    """Concatenate the chunks; refuse non-finite corners and corners beyond
    :data:`~lbl_illum.scene.geometry.MAX_COORDINATE`, drop zero-area and duplicate triangles.

    Duplicates (same three corners in any order, also across entries) keep their
    first occurrence; each entry that lost triangles gets one warning.
    """
    for chunk in chunks:
        bad = ~np.isfinite(chunk.vertices).all(axis=(1, 2))
        if bad.any():
            raise InputError(f"{chunk.label}: {plural(int(bad.sum()), 'triangle')} with a NaN or "
                             "infinite vertex coordinate")
        far = (np.abs(chunk.vertices) > MAX_COORDINATE).any(axis=(1, 2))
        if far.any():
            raise InputError(f"{chunk.label}: {plural(int(far.sum()), 'triangle')} with a vertex coordinate "
                             f"beyond ±{MAX_COORDINATE:g} m (a wrong 'units' or exponent?)")
    if not chunks:
        return Triangles(np.zeros((0, 3, 3)), np.zeros(0, np.int32), np.zeros(0, np.int32))
    vertices = np.concatenate([c.vertices for c in chunks]).astype(np.float64)
    owner = np.concatenate([np.full(len(c.vertices), i) for i, c in enumerate(chunks)]).astype(np.int64)
    zero = degenerate_mask(vertices)
    dup = np.zeros(len(vertices), dtype=bool)
    dup[~zero] = duplicate_mask(vertices[~zero])
    n_zero = np.bincount(owner[zero], minlength=len(chunks))
    n_dup = np.bincount(owner[dup], minlength=len(chunks))
    for chunk, z, d in zip(chunks, n_zero, n_dup):
        if z or d:
            what = " and ".join(f"{n} {kind}" for n, kind in ((z, "zero-area"), (d, "duplicate")) if n)
            warnings.append(f"{chunk.label}: dropped {what} {'triangle' if z + d == 1 else 'triangles'}")
    keep = ~(zero | dup)
    return Triangles(
        vertices=vertices[keep],
        material=np.concatenate([c.material for c in chunks])[keep].astype(np.int32),
        sphere=np.concatenate([c.sphere for c in chunks])[keep].astype(np.int32),
    )
