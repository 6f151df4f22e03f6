"""vcm.render gives the command line's image, bit for bit (the CLI writes 32-bit float EXR,
lossless), for the same settings."""

import subprocess

import numpy as np
import pytest

import vcm

CASES = [
    # (scene, algorithm, extra CLI arguments, extra keyword arguments)
    ("cornell-sun", "pt", [], {}),
    ("cornell-sun", "vcm", [], {}),
    ("cornell-area-mirror", "vcm", ["--spectral"], {"spectral": True}),
    ("scenes/cornell-fluorescent.xml", "bpt", ["--max-length", "5"], {"max_length": 5}),
    ("cornell-area-mirror", "pt", ["--light-sampler", "power"], {"light_sampler": "power"}),
    ("cornell-area-mirror", "pt", ["--sampler", "independent"], {"sampler": "independent"}),
    ("cornell-env", "bpt", ["--mis-compensation", "off"], {"mis_compensation": False}),
    ("cornell-point", "vcm", ["--parallelism", "iterations"], {"parallelism": "iterations"}),
    ("cornell-point", "vcm", ["--parallelism", "pixels"], {"parallelism": "iterations"}),
    ("cornell-fog", "vcm", [], {}),
    ("cornell-fog", "bpm", ["--volume-radius-factor", "0.05"], {"volume_radius_factor": 0.05}),
]


@pytest.mark.parametrize("scene,algorithm,cli_args,kwargs", CASES)
def test_render_equals_cli(tmp_path, root, vcm_bin, scene, algorithm, cli_args, kwargs):
    output = tmp_path / "cli.exr"
    scene_arg = str(root / scene) if "/" in scene else scene
    command = [str(vcm_bin), "render", "--scene", scene_arg, "--algorithm", algorithm, "--iterations", "3",
               "--resolution", "40x30", "--seed", "11", "--quiet", "--output", str(output), *cli_args]
    subprocess.run(command, check=True, capture_output=True)
    expected = vcm.read(output)
    image = vcm.render(vcm.load_file(scene_arg), algorithm=algorithm, iterations=3, resolution=(40, 30), seed=11,
                       **kwargs)
    assert image.dtype == np.float32 and image.shape == (30, 40, 3)
    assert image.flags["C_CONTIGUOUS"]
    assert np.isfinite(image).all() and image.mean() > 0.0
    assert np.array_equal(image, expected), f"max difference {np.abs(image - expected).max()}"
    # The comparison has power: another seed differs.
    other = vcm.render(vcm.load_file(scene_arg), algorithm=algorithm, iterations=3, resolution=(40, 30), seed=12,
                       **kwargs)
    assert not np.array_equal(other, expected)


def test_checkpoints_are_shared_with_the_cli(tmp_path, vcm_bin):
    """A checkpoint of `vcm render` resumes in Python, and a Python checkpoint in `vcm render`."""
    common = ["--scene", "cornell-sun", "--algorithm", "vcm", "--resolution", "24x16", "--seed", "4", "--quiet"]
    cli_checkpoint = tmp_path / "cli.ckpt"
    subprocess.run([str(vcm_bin), "render", *common, "--iterations", "2", "--checkpoint", str(cli_checkpoint),
                    "--output", str(tmp_path / "two.exr")], check=True, capture_output=True)
    session = vcm.Session.resume(cli_checkpoint)
    assert session.iterations == 2
    session.step(2)
    four = vcm.render(vcm.load_file("cornell-sun"), iterations=4, resolution=(24, 16), seed=4)
    assert np.array_equal(session.image(), four)
    python_checkpoint = tmp_path / "python.ckpt"
    session.checkpoint(python_checkpoint)
    subprocess.run([str(vcm_bin), "render", "--resume", str(python_checkpoint), "--iterations", "5", "--quiet",
                    "--output", str(tmp_path / "five.exr")], check=True, capture_output=True)
    five = vcm.render(vcm.load_file("cornell-sun"), iterations=5, resolution=(24, 16), seed=4)
    assert np.array_equal(vcm.read(tmp_path / "five.exr"), five)
    assert not np.array_equal(five, four)
