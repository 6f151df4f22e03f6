"""Sessions: stepping gives the image of one render call; checkpoints resume exactly; the
technique images sum to the image; the variance estimate is usable for the Z-test."""

import numpy as np
import pytest

import vcm

SMALL = {"resolution": (32, 24), "seed": 3}


@pytest.mark.parametrize("algorithm", ["pt", "vcm", "ppm"])
def test_stepping_equals_one_call(algorithm):
    scene = vcm.load_file("cornell-sun")
    session = vcm.Session(scene, algorithm=algorithm, **SMALL)
    assert session.iterations == 0
    assert session.step() == 1
    assert session.step(3) == 4
    assert session.iterations == 4
    one_call = vcm.render(scene, algorithm=algorithm, iterations=4, **SMALL)
    assert np.array_equal(session.image(), one_call)
    assert not np.array_equal(session.image(), vcm.render(scene, algorithm=algorithm, iterations=3, **SMALL))


def test_checkpoint_resumes_exactly(tmp_path):
    scene = vcm.load_file("cornell-area-mirror")
    session = vcm.Session(scene, algorithm="bpt", **SMALL)
    session.step(2)
    path = tmp_path / "state.ckpt"
    session.checkpoint(path)
    resumed = vcm.Session.resume(path)
    assert resumed.iterations == 2 and resumed.resolution == (32, 24)
    resumed.step(2)
    assert np.array_equal(resumed.image(), vcm.render(scene, algorithm="bpt", iterations=4, **SMALL))


@pytest.mark.parametrize("algorithm", ["vcm", "bpt", "lt"])
def test_technique_images_sum_to_the_image(algorithm):
    session = vcm.Session(vcm.load_file("cornell-sun"), algorithm=algorithm, techniques=True, technique_length=3,
                          **SMALL)
    session.step(2)
    images = session.techniques()
    image = session.image().astype(np.float64)
    families = ["emitter-hit", "next-event", "light-tracing", "connection", "merging"]
    assert all(name in images for name in families)
    family_parts = [images[name].astype(np.float64) for name in families]
    technique_parts = [v.astype(np.float64) for k, v in images.items() if k not in families]
    assert len(technique_parts) > 3
    by_family = sum(family_parts)
    for parts in (family_parts, technique_parts):
        total = sum(parts)
        magnitude = sum(np.abs(p) for p in parts)
        # Within float32 rounding of the sum of their magnitudes: a few ulps per addition (the
        # Rust engine test's bound, crates/render/tests/vcm_technique_images.rs).
        tolerance = 4.0 * 2.0 ** -23 * (len(parts) + 2) * (magnitude + np.abs(image)) + 1e-30
        assert (np.abs(total - image) <= tolerance).all(), np.abs(total - image).max()
    # Power: dropping one family that contributes breaks the sum.
    contributing = [n for n in families if np.abs(images[n]).sum() > 1e-3 * np.abs(image).sum()]
    assert contributing
    missing = by_family - images[contributing[0]]
    assert np.abs(missing - image).max() > 1e-3 * np.abs(image).max()


def test_variance_supports_the_z_test():
    scene = vcm.load_file("cornell-sun")
    runs = []
    for seed in (1, 2):
        session = vcm.Session(scene, algorithm="pt", resolution=(24, 16), seed=seed)
        session.step(16)
        runs.append((session.image(), session.variance()))
    (a, va), (b, vb) = runs
    assert va.shape == a.shape and (va >= 0).all() and va.max() > 0
    # Two independent renders of the same scene pass the per-pixel Z-test ...
    result = vcm.compare(a, b, variance_a=va, variance_b=vb)
    assert result["z_test"]["passed"], result
    # ... and a 30 % brighter one fails it (pt at 16 samples: a few percent relative error).
    result = vcm.compare(a * 1.3, b, variance_a=va * 1.69, variance_b=vb)
    assert not result["z_test"]["passed"], result
