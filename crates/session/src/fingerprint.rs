//! What a render's scene was built from, as hashes: for a scene file, the bytes of every file
//! the loader read (the file, its includes, meshes, textures, environment maps, spectrum
//! files) and the `-D` parameters; for a built-in scene, its mask and resolution. A checkpoint
//! records it, and `--resume` refuses a scene that no longer matches.
//!
//! Hash: 64-bit FNV-1a (offset basis 0xcbf29ce484222325, prime 0x100000001b3), stable across
//! platforms and releases. It detects accidental changes (an edited file), not adversarial
//! ones.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

/// 64-bit FNV-1a, fed incrementally.
#[derive(Clone, Copy, Debug)]
pub struct Fnv1a(u64);

impl Default for Fnv1a {
    fn default() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv1a {
    /// Feeds `bytes`.
    pub fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.0 ^= u64::from(*b);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }

    /// Feeds a length-prefixed field, so that field boundaries cannot shift.
    pub fn field(&mut self, bytes: &[u8]) {
        self.write(&(bytes.len() as u64).to_le_bytes());
        self.write(bytes);
    }

    /// The hash so far.
    pub fn finish(self) -> u64 {
        self.0
    }
}

/// What a scene was built from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Fingerprint {
    /// One hash over everything below (and, for built-in scenes, the mask and resolution).
    pub hash: u64,
    /// Every file the loader read, in the order first read (the scene file first), with the
    /// hash of its bytes. Empty for built-in scenes.
    pub files: Vec<(PathBuf, u64)>,
}

impl Fingerprint {
    /// A built-in scene: its mask and resolution (pixels).
    pub fn builtin(mask: u32, (width, height): (u32, u32)) -> Self {
        let mut h = Fnv1a::default();
        h.field(b"builtin");
        for v in [mask, width, height] {
            h.write(&v.to_le_bytes());
        }
        Self { hash: h.finish(), files: Vec::new() }
    }

    /// A scene file: the bytes of each of `files` (read again now) and the `defines`.
    pub fn of_files(files: &[PathBuf], defines: &[String]) -> Result<Self> {
        let files = files
            .iter()
            .map(|path| {
                let bytes = std::fs::read(path).with_context(|| format!("cannot read '{}'", path.display()))?;
                let mut h = Fnv1a::default();
                h.write(&bytes);
                Ok((path.clone(), h.finish()))
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Self::from_parts(files, defines))
    }

    /// Combines per-file hashes and the defines into a fingerprint.
    pub fn from_parts(files: Vec<(PathBuf, u64)>, defines: &[String]) -> Self {
        let mut h = Fnv1a::default();
        h.field(b"files");
        for (path, hash) in &files {
            h.field(path.as_os_str().as_encoded_bytes());
            h.write(&hash.to_le_bytes());
        }
        h.field(b"defines");
        for define in defines {
            h.field(define.as_bytes());
        }
        Self { hash: h.finish(), files }
    }

    /// Why the scene now (`self`) is not the one `recorded` describes, naming the first file
    /// that changed; `None` when they match.
    pub fn difference(&self, recorded: &Fingerprint) -> Option<String> {
        if self.hash == recorded.hash {
            return None;
        }
        let name = |index: usize, path: &Path| {
            if index == 0 { format!("scene file '{}'", path.display()) } else { format!("'{}'", path.display()) }
        };
        for (index, (path, hash)) in recorded.files.iter().enumerate() {
            match self.files.iter().find(|(p, _)| p == path) {
                Some((_, now)) if now != hash => {
                    let read_by = if index == 0 { String::new() } else { ", which the scene reads,".to_string() };
                    return Some(format!("{}{read_by} changed since the checkpoint was written", name(index, path)));
                }
                None => {
                    return Some(format!(
                        "the scene no longer reads {}, which it read when the checkpoint was written",
                        name(index, path)
                    ));
                }
                _ => {}
            }
        }
        if let Some((path, _)) = self.files.iter().find(|(p, _)| !recorded.files.iter().any(|(q, _)| q == p)) {
            return Some(format!(
                "the scene now also reads '{}', which it did not when the checkpoint was written",
                path.display()
            ));
        }
        Some(if self.files.is_empty() {
            "the built-in scene differs from the one the checkpoint was rendered with".to_string()
        } else {
            "the scene's parameters differ from the checkpoint's".to_string()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fnv1a_matches_the_published_test_vectors() {
        // From the FNV reference test suite (Noll): "" and "a" and "foobar".
        for (text, expected) in
            [("", 0xcbf2_9ce4_8422_2325u64), ("a", 0xaf63_dc4c_8601_ec8c), ("foobar", 0x8594_4171_f739_67e8)]
        {
            let mut h = Fnv1a::default();
            h.write(text.as_bytes());
            assert_eq!(h.finish(), expected, "{text:?}");
        }
    }

    #[test]
    fn differences_name_the_changed_file() {
        let parts = |a: u64, b: u64| vec![(PathBuf::from("s.xml"), a), (PathBuf::from("m.ply"), b)];
        let recorded = Fingerprint::from_parts(parts(1, 2), &["x=1".into()]);
        assert_eq!(Fingerprint::from_parts(parts(1, 2), &["x=1".into()]).difference(&recorded), None);
        let message = Fingerprint::from_parts(parts(9, 2), &["x=1".into()]).difference(&recorded).unwrap();
        assert!(message.starts_with("scene file 's.xml' changed"), "{message}");
        let message = Fingerprint::from_parts(parts(1, 9), &["x=1".into()]).difference(&recorded).unwrap();
        assert!(message.starts_with("'m.ply', which the scene reads, changed"), "{message}");
        let mut more = parts(1, 2);
        more.push((PathBuf::from("t.png"), 3));
        let message = Fingerprint::from_parts(more, &["x=1".into()]).difference(&recorded).unwrap();
        assert!(message.contains("now also reads 't.png'"), "{message}");
        let message = Fingerprint::from_parts(parts(1, 2), &["x=2".into()]).difference(&recorded).unwrap();
        assert!(message.contains("parameters differ"), "{message}");
        assert_ne!(Fingerprint::builtin(1, (4, 4)), Fingerprint::builtin(1, (4, 5)));
    }
}
