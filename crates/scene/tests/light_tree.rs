//! The light tree's pmf: it sums to one, `sample` and `probability` agree, `sample`'s
//! frequencies follow `probability` (chi-square), and a light gets probability zero only where
//! it cannot light the point (checked by evaluating the light).

use std::sync::Arc;

use math::{Frame, Rng, Vec3, warp};
use scene::desc::{LightDesc, ProjectorModel, TextureImage, UvTransform};
use scene::light::{AreaLight, BoundingSphere, Light, ProjectorLight, SpotLight, TexturedTriangleLight};
use scene::light_selection::light_selection_weights;
use scene::light_tree::LightTree;
use scene::shape::Triangle;
use scene::texture::Texture;
use spectrum::Rgb;

fn sphere() -> BoundingSphere {
    BoundingSphere { center: Vec3::ZERO, radius: 8.0 }
}

fn point_in_box(rng: &mut Rng, half: f32) -> Vec3 {
    let [a, b] = rng.uniform2();
    Vec3::new(a * 2.0 - 1.0, b * 2.0 - 1.0, rng.uniform() * 2.0 - 1.0) * half
}

fn image() -> Arc<Texture> {
    let pixels = (0..12).map(|i| Rgb::new(0.2 + i as f32 * 0.1, 0.5, 1.0 - i as f32 * 0.05)).collect();
    let image = Arc::new(TextureImage { width: 4, height: 3, pixels });
    Arc::new(Texture::Bitmap { image, to_uv: UvTransform::IDENTITY })
}

/// Lights of every finite kind at random places and orientations, plus an environment.
fn lights(seed: u64) -> Vec<Light> {
    let mut rng = Rng::new(seed, 0);
    let mut lights = Vec::new();
    let triangle = |rng: &mut Rng| {
        let c = point_in_box(rng, 3.0);
        let size = 0.1 + 0.5 * rng.uniform();
        let f = Frame::from_z(warp::uniform_sphere(rng.uniform2()));
        Triangle::new(c, c + f.x * size, c + f.y * size)
    };
    for i in 0..40 {
        lights.push(Light::Area(AreaLight::new(triangle(&mut rng), Rgb::new(1.0 + i as f32 * 0.1, 2.0, 0.5))));
    }
    for _ in 0..5 {
        let uvs = [math::Vec2::ZERO, math::Vec2::X, math::Vec2::Y];
        lights.push(Light::TexturedTriangle(TexturedTriangleLight::new(triangle(&mut rng), uvs, image()).unwrap()));
    }
    lights.push(Light::Area(AreaLight::sphere(point_in_box(&mut rng, 2.0), 0.3, false, Rgb::splat(3.0)).unwrap()));
    let n = warp::uniform_sphere(rng.uniform2());
    let f = Frame::from_z(n);
    lights.push(Light::Area(
        AreaLight::disc(point_in_box(&mut rng, 2.0), f.x * 0.4, f.y * 0.2, false, Rgb::splat(2.0)).unwrap(),
    ));
    for _ in 0..3 {
        let intensity = Rgb::splat(1.0 + rng.uniform());
        lights.push(Light::from_desc(&LightDesc::Point { position: point_in_box(&mut rng, 3.0), intensity }).unwrap());
    }
    for i in 0..4 {
        let cutoff = 15.0 + 15.0 * i as f32;
        let axis = warp::uniform_sphere(rng.uniform2());
        let spot = SpotLight::new(point_in_box(&mut rng, 3.0), axis, Rgb::splat(20.0), cutoff, cutoff * 0.5).unwrap();
        let spot = if i == 1 {
            let f = Frame::from_z(axis);
            spot.with_texture(image(), f.x, f.y).unwrap()
        } else {
            spot
        };
        lights.push(Light::Spot(spot));
    }
    for model in [ProjectorModel::Irradiance, ProjectorModel::Intensity] {
        let f = Frame::from_z(warp::uniform_sphere(rng.uniform2()));
        let position = point_in_box(&mut rng, 3.0);
        let projector = ProjectorLight::new(model, position, [f.x, f.y, f.z], image(), 2.0, 50.0, 1.5).unwrap();
        lights.push(Light::Projector(projector));
    }
    let pixels = (0..64).map(|i| Rgb::splat(1.0 + (i % 7) as f32)).collect();
    let gonio = Arc::new(TextureImage { width: 8, height: 8, pixels });
    let desc = LightDesc::Goniometric {
        position: point_in_box(&mut rng, 3.0),
        frame: [Vec3::X, Vec3::Y, Vec3::Z],
        image: gonio,
        intensity: Rgb::splat(0.5),
    };
    lights.push(Light::from_desc(&desc).unwrap());
    lights.push(Light::from_desc(&LightDesc::Constant { radiance: Rgb::splat(0.05) }).unwrap());
    lights
}

fn build_tree(lights: &[Light]) -> (LightTree, Vec<f32>) {
    let powers: Vec<f32> = lights.iter().map(|l| l.power(&sphere())).collect();
    let groups: Vec<u32> = (0..lights.len() as u32).collect();
    let pick = light_selection_weights(&powers, &groups).unwrap();
    (LightTree::build(lights, &sphere(), |i| pick[i as usize]), pick)
}

/// A receiver: a point among the lights and a normal (zero, a medium point, one time in four).
fn receiver(rng: &mut Rng) -> (Vec3, Vec3) {
    let p = point_in_box(rng, 4.0);
    let n = if rng.uniform() < 0.25 { Vec3::ZERO } else { warp::uniform_sphere(rng.uniform2()) };
    (p, n)
}

#[test]
fn pmf_sums_to_one_and_sample_reports_probability() {
    let lights = lights(1);
    let (tree, pick) = build_tree(&lights);
    assert_eq!(tree.node_count(), 2 * (lights.len() - 1) - 1, "one leaf per finite light");
    // Lights that emit in every direction: nothing is ever lost.
    let omni: Vec<Light> = lights
        .iter()
        .filter(|l| {
            matches!(l, Light::Point(_) | Light::Goniometric(_) | Light::Background(_))
                || l.bounds(&sphere()).is_some_and(|b| b.cos_o == -1.0)
        })
        .cloned()
        .collect();
    let (omni_tree, _) = build_tree(&omni);
    let mut omni_sums = Vec::new();
    let mut rng = Rng::new(2, 0);
    for _ in 0..300 {
        let (p, n) = receiver(&mut rng);
        let probabilities: Vec<f32> = (0..lights.len() as u32).map(|i| tree.probability(p, n, i)).collect();
        let sum: f64 = probabilities.iter().map(|&q| f64::from(q)).sum();
        // Mass is lost (sample returns None) only under a node whose bounds reach p while
        // none of its lights do, so with every light possible the pmf sums to one.
        assert!(sum <= 1.0 + 1e-4, "Σ probability = {sum} at {p}, {n}");
        if probabilities.iter().all(|&q| q > 0.0) {
            assert!((sum - 1.0).abs() < 1e-4, "Σ probability = {sum} at {p}, {n} with every light possible");
        }
        // The environment keeps its scene-global probability.
        let env = lights.len() as u32 - 1;
        assert_eq!(tree.probability(p, n, env), pick[env as usize]);
        omni_sums.push((0..omni.len() as u32).map(|i| f64::from(omni_tree.probability(p, n, i))).sum::<f64>());
        for _ in 0..20 {
            let Some((i, pmf)) = tree.sample(p, n, rng.uniform()) else { continue };
            let again = tree.probability(p, n, i);
            assert!(pmf > 0.0 && (pmf - again).abs() <= 1e-5 * pmf, "light {i}: sample {pmf}, probability {again}");
        }
    }
    assert_eq!(omni.len(), 6, "three points, a goniometric light, a sphere, the environment");
    assert!(omni_sums.iter().all(|s| (s - 1.0).abs() < 1e-4), "{omni_sums:?}");
}

/// Upper 0.1 % point of the chi-square distribution with `k` degrees of freedom
/// (Wilson–Hilferty).
fn chi2_critical(k: f64) -> f64 {
    let a = 2.0 / (9.0 * k);
    k * (1.0 - a + 3.0902 * a.sqrt()).powi(3)
}

/// Pearson's statistic over the lights, pooling lights expected fewer than 5 times; returns
/// (statistic, degrees of freedom).
fn chi2(counts: &[u64], expected: &[f64]) -> (f64, f64) {
    let (mut statistic, mut cells, mut pooled_o, mut pooled_e) = (0.0, 0usize, 0.0, 0.0);
    for (&o, &e) in counts.iter().zip(expected) {
        if e < 5.0 {
            pooled_o += o as f64;
            pooled_e += e;
        } else {
            statistic += (o as f64 - e).powi(2) / e;
            cells += 1;
        }
    }
    if pooled_e > 0.0 {
        statistic += (pooled_o - pooled_e).powi(2) / pooled_e;
        cells += 1;
    }
    (statistic, (cells - 1) as f64)
}

#[test]
fn sample_frequencies_follow_probability() {
    let lights = lights(3);
    let (tree, _) = build_tree(&lights);
    let mut rng = Rng::new(4, 0);
    let samples = 200_000u64;
    for _ in 0..3 {
        let (p, n) = receiver(&mut rng);
        // One cell per light and a last one for `None` (the mass the pmf does not cover).
        let mut counts = vec![0u64; lights.len() + 1];
        for _ in 0..samples {
            match tree.sample(p, n, rng.uniform()) {
                Some((i, _)) => counts[i as usize] += 1,
                None => counts[lights.len()] += 1,
            }
        }
        let mut expected: Vec<f64> =
            (0..lights.len() as u32).map(|i| samples as f64 * f64::from(tree.probability(p, n, i))).collect();
        expected.push((samples as f64 - expected.iter().sum::<f64>()).max(0.0));
        let (statistic, k) = chi2(&counts, &expected);
        assert!(statistic < chi2_critical(k), "χ² = {statistic} with {k} degrees of freedom at {p}, {n}");
        // The test has power: a pmf off by 10 % on the most likely light fails.
        let top = (0..lights.len()).max_by(|&a, &b| expected[a].total_cmp(&expected[b])).unwrap();
        let mut wrong = expected.clone();
        wrong[top] *= 1.1;
        let (bad, _) = chi2(&counts, &wrong);
        assert!(bad > chi2_critical(k), "a 10 % error on light {top} passes: χ² = {bad}");
    }
}

/// The luminance a light sends to `p` (times `|cos|` at a surface receiver) over a few
/// direct samples: zero only if the light cannot light `p`.
fn contribution(light: &Light, p: Vec3, n: Vec3, rng: &mut Rng) -> f32 {
    (0..64)
        .filter_map(|_| light.sample_direct(p, rng.uniform2(), &sphere()))
        .map(|d| d.radiance.luminance() * if n == Vec3::ZERO { 1.0 } else { n.dot(d.direction).abs() })
        .sum()
}

#[test]
fn probability_is_zero_only_where_the_light_cannot_contribute() {
    let lights = lights(5);
    let (tree, _) = build_tree(&lights);
    let mut rng = Rng::new(6, 0);
    let mut zeros = vec![0usize; lights.len()];
    for _ in 0..400 {
        let (p, n) = receiver(&mut rng);
        for (i, light) in lights.iter().enumerate() {
            if tree.probability(p, n, i as u32) == 0.0 {
                zeros[i] += 1;
                let c = contribution(light, p, n, &mut rng);
                assert_eq!(c, 0.0, "light {i} ({light:?}) has probability 0 at {p}, {n} but sends {c}");
            }
        }
    }
    // Not vacuous: one-sided triangles and spots are excluded somewhere.
    let spots: usize = lights.iter().zip(&zeros).filter(|(l, _)| matches!(l, Light::Spot(_))).map(|(_, z)| z).sum();
    let areas: usize = lights.iter().zip(&zeros).filter(|(l, _)| matches!(l, Light::Area(_))).map(|(_, z)| z).sum();
    assert!(spots > 100 && areas > 1000, "zeros: spots {spots}, area lights {areas}");
}

#[test]
fn a_spot_gets_most_samples_inside_its_cone_and_none_outside() {
    // A spot over a floor beside a big emitter: pbrt's reason for the tree.
    let spot = SpotLight::new(Vec3::new(0.0, 2.0, 0.0), -Vec3::Y, Rgb::splat(10.0), 20.0, 10.0).unwrap();
    let big = Triangle::new(Vec3::new(5.0, 0.0, -2.0), Vec3::new(5.0, 4.0, -2.0), Vec3::new(5.0, 0.0, 2.0));
    let lights = vec![Light::Spot(spot), Light::Area(AreaLight::new(big, Rgb::splat(5.0)))];
    let (tree, pick) = build_tree(&lights);
    let inside = tree.probability(Vec3::ZERO, Vec3::Y, 0);
    let outside = tree.probability(Vec3::new(3.0, 0.0, 0.0), Vec3::Y, 0);
    assert!(inside > 0.8 && inside > pick[0], "inside the cone: {inside} (global {})", pick[0]);
    assert_eq!(outside, 0.0);
}

#[test]
fn a_large_build_is_balanced() {
    // O(n log n) build: depth stays logarithmic for many small triangles (checked through the
    // pmf of one light staying well above 2^-64 and the node count).
    let mut rng = Rng::new(7, 0);
    let lights: Vec<Light> = (0..100_000)
        .map(|_| {
            let c = point_in_box(&mut rng, 10.0);
            let t = Triangle::new(c, c + Vec3::X * 0.01, c + Vec3::Y * 0.01);
            Light::Area(AreaLight::new(t, Rgb::splat(1.0)))
        })
        .collect();
    let (tree, _) = build_tree(&lights);
    assert_eq!(tree.node_count(), 2 * lights.len() - 1);
    let (i, pmf) = tree.sample(Vec3::new(0.0, 0.0, 20.0), Vec3::ZERO, 0.5).unwrap();
    assert!(pmf > 1e-9 && (tree.probability(Vec3::new(0.0, 0.0, 20.0), Vec3::ZERO, i) - pmf).abs() <= 1e-5 * pmf);
}
