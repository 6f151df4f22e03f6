//! How next-event estimation and light sub-paths pick a light: the selection weights from the
//! lights' powers and the emitters they belong to. It does not sample (the scene keeps a
//! [`math::Distribution1D`] over these weights).
//!
//! An *emitter* is what a scene file names: one `<emitter>`, or one emitting shape, which the
//! scene splits into one light per triangle. The defensive half of the mixture is uniform over
//! emitters, not over lights: counted per light, a finely tessellated emitting sphere of 32 512
//! triangles beside seven other emitters took almost all of that half, and left a spot light
//! 0.5 × its power share of the samples (Mitsuba 3 gives each emitter the same share, and samples
//! a mesh's triangles by area).

/// Light selection weights (proportional to the pick probabilities; they sum to 1 when any
/// light emits) from each light's emitted power `powers[i]` (watts, any positive scale) and the
/// emitter `groups[i]` it belongs to (any ids; lights with equal ids form one emitter):
///
/// `w_i = ½ · P_i / Σ P + ½ · (1 / G) · P_i / P_group(i)`
///
/// with `G` the number of emitters with positive power. Half in proportion to power, half
/// uniform over emitters, and within an emitter in proportion to power (for a mesh of constant
/// radiance, to area). Pure power selection starves a weak light beside a strong one (a spot
/// beside an environment with 2.5 % of the power was picked by 1 sample in 40 and left pixels it
/// lights without a sample); pure uniform selection wastes samples on weak lights. The
/// mixture's probability is at least half of either's, so its variance is at most twice
/// theirs wherever they do well. Lights of zero power are never picked; if every light has zero
/// power (or there are none), nothing is (all weights zero). With one light per emitter, equal
/// powers give equal probabilities.
///
/// Returns an error when `groups` and `powers` differ in length.
pub fn light_selection_weights(powers: &[f32], groups: &[u32]) -> Result<Vec<f32>, String> {
    if powers.len() != groups.len() {
        return Err(format!("{} light powers but {} emitter groups", powers.len(), groups.len()));
    }
    let positive = |p: f32| p > 0.0 && p.is_finite();
    let mut group_power = std::collections::HashMap::<u32, f64>::new();
    for (&p, &g) in powers.iter().zip(groups) {
        if positive(p) {
            *group_power.entry(g).or_default() += f64::from(p);
        }
    }
    let total: f64 = group_power.values().sum();
    if group_power.is_empty() || !(total.is_finite() && total > 0.0) {
        return Ok(vec![0.0; powers.len()]);
    }
    let emitters = group_power.len() as f64;
    Ok(powers
        .iter()
        .zip(groups)
        .map(|(&p, g)| {
            if !positive(p) {
                return 0.0;
            }
            let p = f64::from(p);
            (0.5 * p / total + 0.5 / emitters * p / group_power[g]) as f32
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::light_selection_weights;

    fn probabilities(powers: &[f32], groups: &[u32]) -> Vec<f32> {
        let w = light_selection_weights(powers, groups).unwrap();
        let total: f32 = w.iter().sum();
        assert!((total - 1.0).abs() < 1e-4, "weights sum to {total}");
        w
    }

    #[test]
    fn half_power_half_uniform_over_single_lights() {
        // A spot with 2.5 % of the power beside an environment: 0.5 · 0.025 + 0.5 / 2.
        let p = probabilities(&[1.0, 39.0], &[0, 1]);
        assert!((p[0] - 0.2625).abs() < 1e-6 && (p[1] - 0.7375).abs() < 1e-6, "{p:?}");
        // Equal powers stay uniform; a light of zero power is never picked.
        assert_eq!(probabilities(&[3.0, 3.0, 0.0], &[0, 1, 2]), vec![0.5, 0.5, 0.0]);
        // Nothing emits: nothing to pick (all weights zero).
        assert_eq!(light_selection_weights(&[0.0, 0.0], &[0, 1]).unwrap(), vec![0.0, 0.0]);
    }

    #[test]
    fn uniform_half_is_per_emitter_not_per_triangle() {
        // A spot (power 1) beside a mesh emitter of 1000 triangles (power 1 each): the spot gets
        // 0.5 · 1/1001 + 0.5 · 1/2, whatever the tessellation; per light it got 0.5 · 2/1001.
        let mut powers = vec![1.0f32];
        let mut groups = vec![7u32];
        powers.extend(std::iter::repeat_n(1.0, 1000));
        groups.extend(std::iter::repeat_n(3, 1000));
        let p = probabilities(&powers, &groups);
        let spot = 0.5 / 1001.0 + 0.25;
        assert!((p[0] - spot).abs() < 1e-6, "spot {}", p[0]);
        // Within the mesh, in proportion to power.
        let mut powers = vec![1.0f32, 1.0, 3.0];
        let p = probabilities(&powers, &[0, 1, 1]);
        let expected = [0.5 * 0.2 + 0.25, 0.5 * 0.2 + 0.25 * 0.25, 0.5 * 0.6 + 0.25 * 0.75];
        for (got, want) in p.iter().zip(expected) {
            assert!((got - want).abs() < 1e-6, "{p:?} against {expected:?}");
        }
        powers.push(1.0);
        assert!(light_selection_weights(&powers, &[0, 1, 1]).is_err());
    }
}
