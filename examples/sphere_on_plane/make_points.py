"""Write points.pts: sensor points on the sphere of the sphere-on-plane example.

Run from anywhere:  python examples/sphere_on_plane/make_points.py
The output is deterministic; re-running reproduces the committed file exactly.

The sphere has radius 1 and centre (0, 0, 1), so it touches the plane z = 0 at the origin.
Points lie on the sphere surface at elevation angles gamma (measured from the horizontal
plane through the centre) from -85 to +85 degrees in 5 degree steps, each at the four
azimuths phi = 0, 90, 180, 270 degrees (anticlockwise from +x).  Each sensor faces
outwards, along the sphere normal:

    normal = (cos g cos p, cos g sin p, sin g),    point = (0, 0, 1) + normal
"""

import math
from pathlib import Path

HERE = Path(__file__).resolve().parent

CENTER = (0.0, 0.0, 1.0)
RADIUS = 1.0
ELEVATIONS = range(-85, 86, 5)  # degrees
AZIMUTHS = (0, 90, 180, 270)  # degrees


def unit(x):
    """Round away floating-point dust (cos 90 deg = 6e-17) so the file reads cleanly."""
    return round(x, 15) + 0.0  # + 0.0 turns -0.0 into 0.0


def fmt(x):
    return f"{x + 0.0:.9g}"


def main():
    lines = [
        "# Sphere r=1 centred (0,0,1) on the plane z=0: points on its surface with outward normals, "
        "elevation -85..85 deg step 5 (from the horizontal through the centre) x azimuth 0/90/180/270 deg. "
        "Columns: x y z nx ny nz"
    ]
    for g in ELEVATIONS:
        for p in AZIMUTHS:
            gr, pr = math.radians(g), math.radians(p)
            n = (unit(math.cos(gr) * math.cos(pr)), unit(math.cos(gr) * math.sin(pr)), unit(math.sin(gr)))
            pt = tuple(c + RADIUS * ni for c, ni in zip(CENTER, n))
            lines.append(" ".join(fmt(v) for v in pt + n))
    (HERE / "points.pts").write_text("\n".join(lines) + "\n")
    return len(lines) - 1


if __name__ == "__main__":
    print("points.pts:", main(), "points")
