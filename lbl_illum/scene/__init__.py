"""The scene as the user describes it: scene files (TOML, with geometry from OBJ, PLY, STL,
glTF and Radiance ``.rad`` files), triangle geometry and polygons in metres, materials and
what they do with light, camera views, and length units.  Everything here is converted to
metres on the way in; nothing here traces a ray."""
