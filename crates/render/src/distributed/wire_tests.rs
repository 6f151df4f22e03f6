//! Round trips and malformed messages of [`super::wire`].

use scene::FrameBuffer;
use spectrum::Rgb;

use super::wire::{Decision, decode_decision, decode_message, encode_decision, encode_message};
use crate::progressive::IterationResult;
use crate::vcm::{FamilyValues, IterationStats};

fn result() -> IterationResult {
    let mut frame = FrameBuffer::new(3, 2);
    frame.pixels[4] = Rgb { r: f32::NAN, g: -0.0, b: 1e-40 };
    IterationResult {
        iteration: 41,
        frame,
        rejected: 2,
        stats: Some(IterationStats {
            light_vertices: 7,
            radius: 0.25,
            rejected_by_family: [1, 0, 0, 0, 9],
            ..Default::default()
        }),
        family_values: Some(vec![FamilyValues([Rgb { r: 1.0, g: 2.0, b: 3.0 }; 5], [1, 2, 3, 4, 5]); 6]),
        technique_values: Some(vec![Rgb { r: 0.5, g: 0.0, b: 7.0 }; 12]),
    }
}

#[test]
fn messages_round_trip_bit_for_bit() {
    let r = result();
    let bytes = encode_message(true, Some(&r));
    let (stop, back) = decode_message(&bytes, 1).unwrap();
    let back = back.unwrap();
    assert!(stop);
    assert_eq!(bytes, encode_message(true, Some(&back)), "re-encoding gives the same bytes (NaN, -0 kept)");
    assert_eq!((back.iteration, back.rejected, back.stats.unwrap().light_vertices), (41, 2, 7));
    assert_eq!(decode_message(&encode_message(false, None), 2).unwrap().1.map(|r| r.iteration), None);
    for d in [Decision::Continue(12), Decision::Stop(true), Decision::Failed("disk full".into())] {
        assert_eq!(decode_decision(&encode_decision(&d)).unwrap(), d);
    }
}

#[test]
fn malformed_messages_are_errors_naming_the_rank() {
    let bytes = encode_message(false, Some(&result()));
    let error = decode_message(&bytes[..bytes.len() - 1], 2).unwrap_err();
    assert!(error.contains("rank 2"), "{error}");
    let mut longer = bytes.clone();
    longer.push(0);
    assert!(decode_message(&longer, 1).unwrap_err().contains("after its end"));
    assert!(decode_message(&[3], 1).is_err());
    assert!(decode_decision(&[9]).is_err());
}

#[test]
fn a_message_is_12_bytes_per_pixel_plus_a_fixed_header() {
    // docs/distributed.md's communication cost: 12 B per pixel (f32 RGB) + 37 B, + 80 B of
    // VCM statistics (both merging radii among them); + 80 B per pixel with family films,
    // + 12 B per pixel and technique image.
    let mut r = result();
    let pixels = 6;
    assert_eq!(encode_message(false, Some(&r)).len(), 37 + 80 + 12 * pixels + (8 + 80 * 6) + (8 + 12 * 12));
    r.family_values = None;
    r.technique_values = None;
    assert_eq!(encode_message(false, Some(&r)).len(), 37 + 80 + 12 * pixels);
    r.stats = None;
    assert_eq!(encode_message(false, Some(&r)).len(), 37 + 12 * pixels);
    assert_eq!(encode_message(true, None).len(), 2);
    assert_eq!(encode_decision(&Decision::Continue(5)).len(), 9);
}
