"""Errors are Python exceptions with the command line's messages: ValueError for bad settings and
scene files (with file:line:column), FileNotFoundError / OSError for files."""

import numpy as np
import pytest

import vcm


def test_bad_settings_raise_value_error():
    scene = vcm.load_file("cornell-sun")
    with pytest.raises(ValueError, match="unknown algorithm 'nope'"):
        vcm.render(scene, algorithm="nope")
    with pytest.raises(ValueError, match="not both"):
        vcm.render(scene, iterations=2, time=1.0)
    with pytest.raises(ValueError, match="radius-alpha"):
        vcm.render(scene, iterations=1, radius_alpha=2.0, resolution=(8, 8))
    with pytest.raises(ValueError, match="resolution"):
        vcm.render(scene, iterations=1, resolution=(0, 8))
    with pytest.raises(ValueError, match="techniques=True needs an algorithm of the VCM engine"):
        vcm.Session(scene, algorithm="pt", techniques=True)
    with pytest.raises(ValueError, match="techniques=True"):
        vcm.Session(scene, resolution=(8, 8)).techniques()


def test_keyword_errors_are_type_errors_naming_the_keyword():
    scene = vcm.load_file("cornell-sun")
    with pytest.raises(TypeError, match=r"render\(\) got an unexpected keyword argument 'iteration'; it accepts: "
                                        r"algorithm, iterations, time,"):
        vcm.render(scene, iteration=2)
    # Each function accepts only its own: no budget for a Session, no technique images for render.
    with pytest.raises(TypeError, match=r"Session\(\) got an unexpected keyword argument 'iterations'"):
        vcm.Session(scene, iterations=2)
    with pytest.raises(TypeError, match="unexpected keyword argument 'techniques'"):
        vcm.render(scene, techniques=True)
    with pytest.raises(TypeError, match=r"render\(\): seed expects an int >= 0, got 'one'"):
        vcm.render(scene, seed="one")
    with pytest.raises(TypeError, match=r"Session\(\): volume_radius_factor expects a float or None"):
        vcm.Session(scene, volume_radius_factor="big")
    with pytest.raises(TypeError):
        vcm.render(scene, "pt")  # keyword-only, as documented
    # The volume radius is checked as the command line checks it.
    with pytest.raises(ValueError, match="volume"):
        vcm.render(vcm.load_file("cornell-fog"), iterations=1, resolution=(8, 8), volume_radius_factor=-1.0)
    # A constructor error is an exception, not an abort (the 21-parameter constructor aborted).
    with pytest.raises(ValueError, match="volume"):
        vcm.Session(vcm.load_file("cornell-fog"), resolution=(8, 8), volume_radius_factor=-1.0)


def test_unknown_scenes():
    with pytest.raises(ValueError, match="unknown scene 'cornell-nothing'"):
        vcm.load_file("cornell-nothing")
    with pytest.raises(FileNotFoundError, match="missing.xml"):
        vcm.load_file("missing.xml")


def test_scene_file_errors_carry_file_line_and_column(tmp_path):
    path = tmp_path / "broken.xml"
    path.write_text('<scene version="3.0.0">\n  <shape type="sphere">\n    <float name="radius" value="x"/>\n'
                    '  </shape>\n</scene>\n')
    with pytest.raises(ValueError) as error:
        vcm.load_file(str(path))
    assert f"{path}:3:" in str(error.value), str(error.value)
    path.write_text('<scene version="3.0.0">\n  <shape type="sphere">\n')
    with pytest.raises(ValueError, match="broken.xml:"):
        vcm.load_file(str(path))


def test_image_errors(tmp_path):
    with pytest.raises(OSError, match="nothing.exr"):
        vcm.read(tmp_path / "nothing.exr")
    with pytest.raises(ValueError, match=r"shape \(height, width, 3\)"):
        vcm.write(tmp_path / "a.exr", np.zeros((4, 4)))
    with pytest.raises(OSError, match="a.bmpx"):
        vcm.write(tmp_path / "a.bmpx", np.zeros((4, 4, 3)))
    with pytest.raises(ValueError, match="image sizes differ"):
        vcm.compare(np.zeros((4, 4, 3)), np.zeros((4, 5, 3)))
    with pytest.raises(ValueError, match="both variance_a and variance_b"):
        vcm.compare(np.zeros((4, 4, 3)), np.zeros((4, 4, 3)), variance_a=np.zeros((4, 4, 3)))
