"""vcm: a physically based renderer built around vertex connection and merging.

Images are numpy float32 arrays of shape (height, width, 3), linear sRGB, top row first.

    import vcm
    scene = vcm.load_file("cornell-sun")           # a built-in scene, or a .xml / .pbrt file
    image = vcm.render(scene, algorithm="vcm", iterations=16)
    vcm.write("render.exr", image)

See docs/python.md for the whole API.
"""

from ._vcm import (
    ALGORITHMS,
    Scene,
    Session,
    __version__,
    compare,
    load_file,
    read,
    render,
    scenes,
    write,
)

__all__ = [
    "ALGORITHMS",
    "Scene",
    "Session",
    "__version__",
    "compare",
    "load_file",
    "read",
    "render",
    "scenes",
    "write",
]
