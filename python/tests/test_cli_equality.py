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
