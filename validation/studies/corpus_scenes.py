"""The accuracy corpus: daylit interiors, most of them modelled by others, each under an
overcast sky and a sunny hour (validation/corpus/README.md).

Each :class:`CorpusScene` names its scene files per sky and its sensor points, relative
to ``validation/corpus/`` of a source checkout, and its role: ``"choose"`` scenes are
the ones the presets and defaults are chosen on, ``"report"`` scenes are held out and
only reported.  The furnished office is generated (:func:`prepare`) into its ``build/``
folder; the others are files in the repository.  Converged references live in
``validation/data/corpus/NAME-SKY.json`` (``validation/corpus_reference.py``).
"""

from __future__ import annotations

import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

__all__ = ["CorpusScene", "SCENES", "SKIES", "corpus_root", "reference_path", "prepare", "cases"]

#: The two daylight conditions of every scene.
SKIES = ("overcast", "sunny")
#: Triangles of the generated furnished office.
FURNISHED_TRIANGLES = 10_000


@dataclass(frozen=True)
class CorpusScene:
    """One interior of the corpus.

    name : short name;  folder : under ``validation/corpus/``
    files : scene file per sky (relative to the folder);  points : ``.pts`` (relative to the folder)
    role : ``"choose"`` (settings are chosen on it) or ``"report"`` (held out)
    source : who modelled it, and the licence;  description : what it is, in a line
    """

    name: str
    folder: str
    files: dict
    points: str
    role: str
    source: str
    description: str


SCENES = (
    CorpusScene("office", "office", {"overcast": "overcast.toml", "sunny": "sunny.toml"}, "grid.pts", "choose",
                "this project (examples/office)",
                "4 x 6 x 3 m side-lit office, one 3 x 1.5 m window, 77 sensors"),
    CorpusScene("deep-room", "deep-room", {"overcast": "glazed-overcast.toml", "sunny": "glazed-sunny.toml"},
                "grid.pts", "choose", "this project (the deep-room study)",
                "4 x 12 x 3 m room, one glazed 3 x 1.5 m window, 33 sensors"),
    CorpusScene("lbnl-open-office", "lbnl-open-office", {"overcast": "overcast.toml", "sunny": "sunny.toml"},
                "grid.pts", "choose", "LBNL frads test objects (BSD-style licence)",
                "12 x 14 m open-plan office, cubicles, desks, overhang, two glazing bands, 110 sensors"),
    CorpusScene("deep-room-opening", "deep-room", {"overcast": "opening-overcast.toml",
                                                    "sunny": "opening-sunny.toml"},
                "grid.pts", "report", "this project (the deep-room study)",
                "the deep room with an unglazed opening and no portal drawn, 33 sensors"),
    CorpusScene("furnished-office", "furnished-office/build", {"overcast": "overcast.toml", "sunny": "sunny.toml"},
                "grid.pts", "report", "this project (examples/furnished_office, 10,000 triangles)",
                "the office with desks, chairs, bookcases, a coffered ceiling, 77 sensors"),
    CorpusScene("lightshelf-office", "lightshelf-office", {"overcast": "overcast.toml", "sunny": "sunny.toml"},
                "grid.pts", "report", "Radiance's obj/virtual, G. Ward, LBL (Radiance licence)",
                "6 x 8 x 3.2 m drafting office, light shelf with a mirror top, mirror-glass neighbour, 59 sensors"),
    CorpusScene("cabin", "cabin", {"overcast": "overcast.toml", "sunny": "sunny.toml"}, "grid.pts", "report",
                "Radiance's cabin tutorial, obj/cabin (Radiance licence)",
                "furnished 27 x 18 ft log cabin, cathedral ceiling, 15 windows on four walls, 37 sensors"),
    CorpusScene("b90-office", "b90-office", {"overcast": "overcast.toml", "sunny": "sunny.toml"}, "grid.pts",
                "report", "Radiance's obj/office, LBL building 90 (Radiance licence)",
                "furnished 15 x 15 ft private office, window behind an open venetian blind, 64 sensors"),
)


def corpus_root() -> Path | None:
    """``validation/corpus/`` of the source checkout, or None when not run from one."""
    from . import repository_root

    root = repository_root()
    if root is None or not (root / "validation" / "corpus").is_dir():
        return None
    return root / "validation" / "corpus"


def reference_path(scene: CorpusScene, sky: str) -> Path:
    """Where the converged reference of ``scene`` under ``sky`` is kept."""
    return corpus_root().parent / "data" / "corpus" / f"{scene.name}-{sky}.json"


def cases(names=None, roles=None):
    """(scene, sky) pairs of the corpus, optionally only those named or of those roles."""
    return [(s, sky) for s in SCENES for sky in SKIES
            if (names is None or s.name in names) and (roles is None or s.role in roles)]


def prepare(scene: CorpusScene) -> tuple[dict, Path]:
    """The scene files per sky (absolute paths) and the points file, making the generated
    scene first if it is missing."""
    root = corpus_root()
    folder = root / scene.folder
    if scene.name == "furnished-office" and not all((folder / f).is_file() for f in scene.files.values()):
        _make_furnished(folder)
    return {sky: folder / f for sky, f in scene.files.items()}, folder / scene.points


def _make_furnished(folder: Path) -> None:
    """Generate the furnished office into ``folder`` and write its two sky variants."""
    script = corpus_root().parents[1] / "examples" / "furnished_office" / "make_furnished_office.py"
    subprocess.run([sys.executable, str(script), "--triangles", str(FURNISHED_TRIANGLES), "--out", str(folder)],
                   check=True, capture_output=True)
    text = (folder / "scene.toml").read_text()
    body = text[:text.index("[sky]")]
    (folder / "overcast.toml").write_text(body + '[sky]\ntype = "cie-overcast"\nhorizontal_illuminance = 10000\n'
                                                 'ground_reflectance = 0.2\n')
    (folder / "sunny.toml").write_text(body + '[sky]\nweather = "../../weather/oakland-feb11.epw"\n'
                                              'time = "02-11 11:30"\n')
