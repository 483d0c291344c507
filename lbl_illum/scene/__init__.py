"""The scene as the user describes it: scene files (TOML, with geometry from OBJ, PLY, STL,
glTF and Radiance ``.rad`` files), triangle geometry and polygons in metres, materials and
what they do with light, luminaires and their photometric files, camera views, and length
units.  Everything here is converted to
metres on the way in; nothing here traces a ray."""

from .._public import public_surface

#: The public names of this layer, by module (imported when first used).
__all__, __getattr__, __dir__ = public_surface(globals(), {
    "scenefile": ("Scene", "load_scene", "scene_from_dict"),
    "geometry": ("Triangles", "box_triangles", "polygon_triangles", "rectangle_triangles", "sphere_triangles"),
    "materials": ("Material", "MaterialTable", "DIFFUSE", "GLASS", "MIRROR", "LIGHT", "PLASTIC", "OPENING",
                  "TRANSLUCENT"),
    "views": ("View", "view_from_file", "view_from_string"),
    "units": ("metres_per_unit",),
    "luminaires": ("Luminaire",),
    "photometric": ("Photometry", "read_photometry"),
})
