#!/usr/bin/env python3
"""Renders a Mitsuba 3 scene file with Mitsuba itself (scalar_rgb variant) for manual comparisons:
`python3 scripts/mitsuba-render.py SCENE.xml OUT.exr SPP`. Needs the `mitsuba` package."""
import sys

import mitsuba as mi

mi.set_variant("scalar_rgb")
scene = mi.load_file(sys.argv[1])
image = mi.render(scene, spp=int(sys.argv[3]))
mi.Bitmap(image).write(sys.argv[2])
