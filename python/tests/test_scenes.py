"""Scenes: built-ins by name and id, scene files with Mitsuba parameters."""

import numpy as np

import vcm


def test_builtins_by_name_and_id():
    listed = vcm.scenes()
    names = [s["name"] for s in listed]
    assert "cornell-sun" in names and "cornell-area-mirror" in names
    by_id = vcm.load_file(str(listed[1]["id"]))
    by_name = vcm.load_file(listed[1]["name"])
    assert by_id.name == by_name.name == listed[1]["name"]
    assert by_name.resolution == (512, 512)
    a = vcm.render(by_id, iterations=1, resolution=(16, 12))
    assert np.array_equal(a, vcm.render(by_name, iterations=1, resolution=(16, 12)))


def test_scene_file_parameters(tmp_path):
    path = tmp_path / "sphere.xml"
    path.write_text(
        '<scene version="3.0.0">\n'
        '  <default name="res" value="20"/>\n'
        '  <default name="emit" value="1"/>\n'
        '  <sensor type="perspective"><float name="fov" value="40"/>\n'
        '    <film type="hdrfilm"><integer name="width" value="$res"/><integer name="height" value="$res"/>'
        '<rfilter type="box"/></film>\n'
        '  </sensor>\n'
        '  <emitter type="constant"><rgb name="radiance" value="$emit"/></emitter>\n'
        "</scene>\n"
    )
    scene = vcm.load_file(str(path), res=12, emit=0.5)
    assert scene.resolution == (12, 12)
    image = vcm.render(scene, algorithm="pt", iterations=2)
    assert image.shape == (12, 12, 3)
    # A camera inside a constant environment sees its radiance everywhere.
    assert np.allclose(image, 0.5, rtol=1e-5)
    assert np.allclose(vcm.render(vcm.load_file(str(path)), algorithm="pt", iterations=1), 1.0, rtol=1e-5)
