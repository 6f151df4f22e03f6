//! The bytes a rank sends to rank 0 each round (its stop flag and its [`IterationResult`] or
//! none) and the bytes rank 0 broadcasts back (the decision). Little-endian, fixed layout; both
//! ends run the same binary, so there is no versioning. Sizes: see `docs/distributed.md`.

use scene::FrameBuffer;
use spectrum::Rgb;

use crate::progressive::IterationResult;
use crate::vcm::{FamilyValues, IterationStats};

/// Serialises a rank's message of one round: its stop flag and its result, if any.
pub fn encode_message(stop: bool, result: Option<&IterationResult>) -> Vec<u8> {
    let mut out = Vec::new();
    out.push(u8::from(stop));
    let Some(r) = result else {
        out.push(0);
        return out;
    };
    out.push(1);
    put_u64(&mut out, r.iteration);
    put_u64(&mut out, u64::from(r.frame.width));
    put_u64(&mut out, u64::from(r.frame.height));
    put_u64(&mut out, r.rejected);
    put_rgbs(&mut out, &r.frame.pixels);
    match &r.stats {
        Some(s) => {
            out.push(1);
            for v in [s.light_vertices as u64, s.bytes_per_vertex as u64, s.splats as u64, s.rejected] {
                put_u64(&mut out, v);
            }
            for v in s.rejected_by_family {
                put_u64(&mut out, v);
            }
            out.extend_from_slice(&s.radius.to_le_bytes());
            out.extend_from_slice(&s.volume_radius.to_le_bytes());
        }
        None => out.push(0),
    }
    match &r.family_values {
        Some(values) => {
            out.push(1);
            put_u64(&mut out, values.len() as u64);
            for v in values {
                put_rgbs(&mut out, &v.0);
                for count in v.1 {
                    out.extend_from_slice(&count.to_le_bytes());
                }
            }
        }
        None => out.push(0),
    }
    match &r.technique_values {
        Some(values) => {
            out.push(1);
            put_u64(&mut out, values.len() as u64);
            put_rgbs(&mut out, values);
        }
        None => out.push(0),
    }
    out
}

/// Parses a message of [`encode_message`]: (stop flag, result). `from` names the sender in
/// errors.
pub fn decode_message(bytes: &[u8], from: usize) -> Result<(bool, Option<IterationResult>), String> {
    let mut r = Reader { bytes, at: 0, from };
    let stop = r.flag()?;
    if !r.flag()? {
        r.end()?;
        return Ok((stop, None));
    }
    let iteration = r.u64()?;
    let width = r.u32_from_u64()?;
    let height = r.u32_from_u64()?;
    let rejected = r.u64()?;
    let pixels = r.rgbs(width as usize * height as usize)?;
    let stats = if r.flag()? {
        let [light_vertices, bytes_per_vertex, splats, rejected] = [r.u64()?, r.u64()?, r.u64()?, r.u64()?];
        let mut rejected_by_family = [0; 5];
        for v in &mut rejected_by_family {
            *v = r.u64()?;
        }
        Some(IterationStats {
            light_vertices: light_vertices as usize,
            bytes_per_vertex: bytes_per_vertex as usize,
            splats: splats as usize,
            rejected,
            rejected_by_family,
            radius: r.f32()?,
            volume_radius: r.f32()?,
            phases: Default::default(),
        })
    } else {
        None
    };
    let family_values = if r.flag()? {
        let n = r.len()?;
        let mut values = Vec::with_capacity(n.min(bytes.len() / 80));
        for _ in 0..n {
            let rgbs = r.rgbs(5)?;
            let mut counts = [0u32; 5];
            for c in &mut counts {
                *c = r.u32()?;
            }
            values.push(FamilyValues([rgbs[0], rgbs[1], rgbs[2], rgbs[3], rgbs[4]], counts));
        }
        Some(values)
    } else {
        None
    };
    let technique_values = if r.flag()? {
        let n = r.len()?;
        Some(r.rgbs(n)?)
    } else {
        None
    };
    r.end()?;
    let frame = FrameBuffer { width, height, pixels };
    Ok((stop, Some(IterationResult { iteration, frame, rejected, stats, family_values, technique_values })))
}

/// Rank 0's decision after a round.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Decision {
    /// Render another round whose first iteration is this index.
    Continue(u64),
    /// Stop; `true` when a stop flag (a signal) ended the render.
    Stop(bool),
    /// Rank 0 failed (e.g. a checkpoint could not be written); every rank stops with it.
    Failed(String),
}

/// Serialises a [`Decision`].
pub fn encode_decision(decision: &Decision) -> Vec<u8> {
    let mut out = Vec::new();
    match decision {
        Decision::Continue(base) => {
            out.push(0);
            put_u64(&mut out, *base);
        }
        Decision::Stop(interrupted) => out.extend([1, u8::from(*interrupted)]),
        Decision::Failed(message) => {
            out.push(2);
            out.extend_from_slice(message.as_bytes());
        }
    }
    out
}

/// Parses a [`Decision`] broadcast by rank 0.
pub fn decode_decision(bytes: &[u8]) -> Result<Decision, String> {
    let mut r = Reader { bytes, at: 0, from: 0 };
    let decision = match bytes.first() {
        Some(0) => {
            r.at = 1;
            Decision::Continue(r.u64()?)
        }
        Some(1) => {
            r.at = 1;
            Decision::Stop(r.flag()?)
        }
        Some(2) => return Ok(Decision::Failed(String::from_utf8_lossy(&bytes[1..]).into_owned())),
        _ => return Err(format!("a decision from rank 0 of {} bytes that starts with no known tag", bytes.len())),
    };
    r.end()?;
    Ok(decision)
}

fn put_u64(out: &mut Vec<u8>, v: u64) {
    out.extend_from_slice(&v.to_le_bytes());
}

fn put_rgbs(out: &mut Vec<u8>, values: &[Rgb]) {
    out.reserve(values.len() * 12);
    for v in values {
        for c in [v.r, v.g, v.b] {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
}

/// A cursor over a received message; errors name the sender and the offset.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
    from: usize,
}

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> Result<[u8; N], String> {
        let slice = self.bytes.get(self.at..self.at + N).ok_or_else(|| {
            format!(
                "the message from rank {} ends at byte {} where {N} more were expected",
                self.from,
                self.bytes.len()
            )
        })?;
        self.at += N;
        Ok(slice.try_into().unwrap_or([0; N]))
    }

    fn u64(&mut self) -> Result<u64, String> {
        self.take::<8>().map(u64::from_le_bytes)
    }

    fn u32(&mut self) -> Result<u32, String> {
        self.take::<4>().map(u32::from_le_bytes)
    }

    fn f32(&mut self) -> Result<f32, String> {
        self.take::<4>().map(f32::from_le_bytes)
    }

    fn flag(&mut self) -> Result<bool, String> {
        match self.take::<1>()? {
            [0] => Ok(false),
            [1] => Ok(true),
            [other] => Err(format!("the message from rank {} has flag {other} at byte {}", self.from, self.at - 1)),
        }
    }

    fn u32_from_u64(&mut self) -> Result<u32, String> {
        let v = self.u64()?;
        u32::try_from(v).map_err(|_| format!("the message from rank {} names an image dimension of {v}", self.from))
    }

    /// A count of 12-byte values that the rest of the message can hold.
    fn len(&mut self) -> Result<usize, String> {
        let n = self.u64()?;
        usize::try_from(n).ok().filter(|&n| n <= self.bytes.len()).ok_or_else(|| {
            format!("the message from rank {} counts {n} values in {} bytes", self.from, self.bytes.len())
        })
    }

    fn rgbs(&mut self, n: usize) -> Result<Vec<Rgb>, String> {
        if n.checked_mul(12).is_none_or(|b| b > self.bytes.len() - self.at.min(self.bytes.len())) {
            return Err(format!(
                "the message from rank {} ends before its {n} colours (at byte {} of {})",
                self.from,
                self.at,
                self.bytes.len()
            ));
        }
        let mut values = Vec::with_capacity(n);
        for _ in 0..n {
            values.push(Rgb { r: self.f32()?, g: self.f32()?, b: self.f32()? });
        }
        Ok(values)
    }

    fn end(&self) -> Result<(), String> {
        if self.at == self.bytes.len() {
            Ok(())
        } else {
            Err(format!("the message from rank {} has {} bytes after its end", self.from, self.bytes.len() - self.at))
        }
    }
}
