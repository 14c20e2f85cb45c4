//! A persistable copy of the baked noise volumes, so that a renderer can start without baking.
//!
//! The base (128³ by default) and detail (32³) volumes are a pure function of the noise seed,
//! their sizes and the bake shaders. Baking them is the bulk of a renderer's creation on a
//! software rasteriser (seconds on lavapipe; milliseconds on a real GPU). A host exports them
//! once ([`crate::Renderer::export_noise_cache`]), stores the bytes (an asset, a file in its
//! cache folder) and hands them to later creations ([`crate::Renderer::with_noise`] with
//! [`crate::NoiseStart::Cache`], C: `NimbusNoiseCacheExt`), which upload them instead of
//! baking: on the device that exported them, the same texels bit for bit. The bake is float
//! arithmetic, so another GPU or driver may bake texels that differ in their last bit from a
//! cache made elsewhere; the cache is accepted there too (its volumes are equally valid noise).
//!
//! Layout (little endian), version 1:
//!
//! | offset | bytes | field |
//! |---|---|---|
//! | 0 | 8 | magic `NIMBUSNC` |
//! | 8 | 4 | format version (1) |
//! | 12 | 4 | bake id: hash of the bake shaders' source, so a changed algorithm never loads stale texels |
//! | 16 | 4 | noise seed |
//! | 20 | 4 | base volume edge |
//! | 24 | 4 | detail volume edge |
//! | 28 | 4 | reserved (0) |
//! | 32 | 8 | payload length in bytes |
//! | 40 | 8 | checksum of bytes 0–39 and the payload (a 64-bit word hash, below) |
//! | 48 | … | payload: base mip 0 then detail mip 0, RGBA8, x fastest, then y, then z |
//!
//! Mip levels are not stored: they are rebuilt on the GPU from mip 0 by the same pass as after
//! a bake, so they match too.

use crate::error::{Error, Result};
use crate::gpu::shaders::NOISE_BAKE_MODULES;
use crate::settings::NoiseSettings;

const MAGIC: &[u8; 8] = b"NIMBUSNC";
const FORMAT_VERSION: u32 = 1;
/// Bytes before the payload.
pub const HEADER_BYTES: usize = 48;

/// FNV-1a (32 bit) over the tokens of the shaders' source text: any change to the code changes
/// it, and an edit of a comment or of the layout does not. Comments (`//` to the end of the
/// line, and `/* */`, nested as WGSL nests them) count as whitespace, every run of whitespace
/// as one space (WGSL has no string literals, so no token holds either), and each module ends
/// in a zero byte, so that text moved from one module to the next changes the id too. Used for
/// the noise cache's bake id (an older cache is refused, so a new id costs hosts one rebake) and
/// the path tracer's source ids (a changed id retires traced references), where a comment
/// edit should cost neither. The modules are the pass's own list (`NOISE_BAKE_MODULES`, which
/// `PASSES` uses), so a module added to the pass is hashed too.
pub(crate) const fn source_hash(modules: &[(&str, &str)]) -> u32 {
    const fn mix(h: u32, byte: u8) -> u32 {
        (h ^ byte as u32).wrapping_mul(0x0100_0193)
    }
    // Whether the text at i starts with the two bytes a, b.
    const fn starts(bytes: &[u8], i: usize, a: u8, b: u8) -> bool {
        i + 1 < bytes.len() && bytes[i] == a && bytes[i + 1] == b
    }
    let mut h: u32 = 0x811c_9dc5;
    let mut p = 0;
    while p < modules.len() {
        let bytes = modules[p].1.as_bytes();
        let mut i = 0;
        // A separator (whitespace or a comment) since the last token byte, and whether the
        // module has had a token yet (leading and trailing whitespace count for nothing).
        let mut separated = false;
        let mut started = false;
        while i < bytes.len() {
            if starts(bytes, i, b'/', b'/') {
                while i < bytes.len() && bytes[i] != b'\n' {
                    i += 1;
                }
                separated = true;
            } else if starts(bytes, i, b'/', b'*') {
                let mut depth = 1;
                i += 2;
                while i < bytes.len() && depth > 0 {
                    if starts(bytes, i, b'/', b'*') {
                        depth += 1;
                        i += 2;
                    } else if starts(bytes, i, b'*', b'/') {
                        depth -= 1;
                        i += 2;
                    } else {
                        i += 1;
                    }
                }
                separated = true;
            } else if bytes[i].is_ascii_whitespace() {
                separated = true;
                i += 1;
            } else {
                if separated && started {
                    h = mix(h, b' ');
                }
                h = mix(h, bytes[i]);
                started = true;
                separated = false;
                i += 1;
            }
        }
        h = mix(h, 0);
        p += 1;
    }
    h
}

/// The identity of the bake this library runs.
pub(crate) const BAKE_ID: u32 = source_hash(NOISE_BAKE_MODULES);

/// A 64-bit hash of the header's first 40 bytes and the payload, a word at a time (fast even
/// unoptimised): each little-endian word is mixed in with a multiply and rotate (the FNV idea
/// on 8-byte words); the tail is zero-padded and the length mixed in last. It catches
/// truncation and corruption, not deliberate forgery (the cache is the host's own data).
fn checksum(header: &[u8], payload: &[u8]) -> u64 {
    const PRIME: u64 = 0x0000_0100_0000_01b3;
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for part in [header, payload] {
        let mut words = part.chunks_exact(8);
        for w in &mut words {
            let w = u64::from_le_bytes(w.try_into().unwrap_or_default());
            h = (h ^ w).wrapping_mul(PRIME).rotate_left(29);
        }
        let mut tail = [0u8; 8];
        tail[..words.remainder().len()].copy_from_slice(words.remainder());
        h = (h ^ u64::from_le_bytes(tail)).wrapping_mul(PRIME);
    }
    (h ^ payload.len() as u64).wrapping_mul(PRIME)
}

fn volume_bytes(edge: u32) -> usize {
    4 * (edge as usize).pow(3)
}

/// The size in bytes of a cache of a `base`³ and a `detail`³ volume; `None` if it does not fit
/// in `usize` (valid settings always fit: edges up to 256 and 128).
pub fn cache_bytes(base: u32, detail: u32) -> Option<usize> {
    let volume = |edge: u32| (edge as usize).checked_pow(3)?.checked_mul(4);
    HEADER_BYTES
        .checked_add(volume(base)?)?
        .checked_add(volume(detail)?)
}

/// The header fields of a cache, as [`NoiseCacheInfo::parse`] read them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NoiseCacheInfo {
    /// Noise seed the volumes were baked with.
    pub seed: u32,
    /// Edge of the base volume.
    pub base_size: u32,
    /// Edge of the detail volume.
    pub detail_size: u32,
}

fn cache_error(reason: impl Into<String>) -> Error {
    Error::NoiseCache(reason.into())
}

fn read_u32(bytes: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]])
}

fn read_u64(bytes: &[u8], at: usize) -> u64 {
    u64::from(read_u32(bytes, at)) | (u64::from(read_u32(bytes, at + 4)) << 32)
}

impl NoiseCacheInfo {
    /// Checks a cache's header, length and checksum, and returns what it holds. A cache
    /// written by a library whose bake differs (another noise algorithm) is refused.
    pub fn parse(bytes: &[u8]) -> Result<Self> {
        if bytes.len() < HEADER_BYTES {
            return Err(cache_error(format!(
                "{} bytes is shorter than the {HEADER_BYTES}-byte header",
                bytes.len()
            )));
        }
        if &bytes[..8] != MAGIC {
            return Err(cache_error(
                "not a Nimbus noise cache (the first 8 bytes are not \"NIMBUSNC\")",
            ));
        }
        let version = read_u32(bytes, 8);
        if version != FORMAT_VERSION {
            return Err(cache_error(format!(
                "format version {version}; this library reads version {FORMAT_VERSION}"
            )));
        }
        let bake = read_u32(bytes, 12);
        if bake != BAKE_ID {
            return Err(cache_error(format!(
                "baked by another noise algorithm (bake id {bake:#010x}, this library's is \
                 {BAKE_ID:#010x}): export a new cache from this library"
            )));
        }
        let info = Self {
            seed: read_u32(bytes, 16),
            base_size: read_u32(bytes, 20),
            detail_size: read_u32(bytes, 24),
        };
        if read_u32(bytes, 28) != 0 {
            return Err(cache_error("reserved header field is not 0"));
        }
        for (name, edge, max) in [
            ("base", info.base_size, 256),
            ("detail", info.detail_size, 128),
        ] {
            if !edge.is_power_of_two() || !(8..=max).contains(&edge) {
                return Err(cache_error(format!(
                    "{name} volume edge {edge} is not a power of two in [8, {max}]"
                )));
            }
        }
        let want = volume_bytes(info.base_size) + volume_bytes(info.detail_size);
        let declared = read_u64(bytes, 32);
        let actual = bytes.len() - HEADER_BYTES;
        if declared != want as u64 || actual != want {
            return Err(cache_error(format!(
                "payload is {actual} bytes (header says {declared}); a {b}³ base and {d}³ \
                 detail volume need {want}: the cache is truncated or damaged",
                b = info.base_size,
                d = info.detail_size
            )));
        }
        if checksum(&bytes[..40], &bytes[HEADER_BYTES..]) != read_u64(bytes, 40) {
            return Err(cache_error(
                "checksum mismatch: the cache is damaged (export it again)",
            ));
        }
        Ok(info)
    }

    /// Whether the cache holds the volumes `noise` asks for; the reason if not.
    pub fn check_matches(&self, noise: &NoiseSettings) -> Result<()> {
        let have = (self.seed, self.base_size, self.detail_size);
        let want = (noise.seed, noise.base_size, noise.detail_size);
        if have != want {
            return Err(cache_error(format!(
                "the cache holds seed {}, base {}³, detail {}³ but the settings ask for seed \
                 {}, base {}³, detail {}³",
                have.0, have.1, have.2, want.0, want.1, want.2
            )));
        }
        Ok(())
    }
}

/// A cache's base and detail mip-0 texels (after [`NoiseCacheInfo::parse`]).
pub(crate) fn payload<'a>(bytes: &'a [u8], info: &NoiseCacheInfo) -> (&'a [u8], &'a [u8]) {
    let payload = &bytes[HEADER_BYTES..];
    payload.split_at(volume_bytes(info.base_size))
}

/// A cache's base and detail texels, once its header and checksum are checked and it holds
/// the volumes `noise` asks for: the one check both the Rust and the C creation use.
pub(crate) fn volumes_for<'a>(
    bytes: &'a [u8],
    noise: &NoiseSettings,
) -> Result<(&'a [u8], &'a [u8])> {
    let info = NoiseCacheInfo::parse(bytes)?;
    info.check_matches(noise)?;
    Ok(payload(bytes, &info))
}

/// Serialises read-back mip-0 texels of both volumes.
pub(crate) fn encode(noise: &NoiseSettings, base: &[u8], detail: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(HEADER_BYTES + base.len() + detail.len());
    out.extend_from_slice(MAGIC);
    for v in [
        FORMAT_VERSION,
        BAKE_ID,
        noise.seed,
        noise.base_size,
        noise.detail_size,
        0,
    ] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&((base.len() + detail.len()) as u64).to_le_bytes());
    out.extend_from_slice(&[0; 8]);
    out.extend_from_slice(base);
    out.extend_from_slice(detail);
    let sum = checksum(&out[..40], &out[HEADER_BYTES..]);
    out[40..48].copy_from_slice(&sum.to_le_bytes());
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn small() -> NoiseSettings {
        NoiseSettings {
            base_size: 8,
            detail_size: 8,
            ..Default::default()
        }
    }

    fn sample() -> Vec<u8> {
        let n = small();
        let base: Vec<u8> = (0..volume_bytes(8)).map(|i| (i * 7 % 251) as u8).collect();
        let detail: Vec<u8> = (0..volume_bytes(8)).map(|i| (i * 3 % 241) as u8).collect();
        encode(&n, &base, &detail)
    }

    #[test]
    fn round_trip_keeps_header_and_texels() {
        let bytes = sample();
        let info = NoiseCacheInfo::parse(&bytes).unwrap();
        assert_eq!((info.seed, info.base_size, info.detail_size), (1, 8, 8));
        info.check_matches(&small()).unwrap();
        let (base, detail) = payload(&bytes, &info);
        assert_eq!(base.len(), 2048);
        assert_eq!(base[10], 70);
        assert_eq!(detail[10], 30);
    }

    #[test]
    fn every_single_byte_flip_is_refused() {
        let bytes = sample();
        // Every header byte and a spread of payload bytes.
        for at in (0..HEADER_BYTES).chain((HEADER_BYTES..bytes.len()).step_by(97)) {
            let mut bad = bytes.clone();
            bad[at] ^= 0x10;
            assert!(NoiseCacheInfo::parse(&bad).is_err(), "flip at byte {at}");
        }
    }

    #[test]
    fn cache_size_is_checked_arithmetic() {
        assert_eq!(
            cache_bytes(128, 32),
            Some(48 + 4 * (128 * 128 * 128 + 32 * 32 * 32))
        );
        assert_eq!(cache_bytes(u32::MAX, 8), None);
    }

    #[test]
    fn truncation_padding_and_garbage_are_refused_with_a_reason() {
        let bytes = sample();
        for cut in [0, 7, 47, 48, bytes.len() - 1] {
            let e = NoiseCacheInfo::parse(&bytes[..cut])
                .unwrap_err()
                .to_string();
            assert!(e.contains("noise cache"), "{e}");
        }
        let mut long = bytes.clone();
        long.push(0);
        let e = NoiseCacheInfo::parse(&long).unwrap_err().to_string();
        assert!(e.contains("truncated or damaged"), "{e}");
        let e = NoiseCacheInfo::parse(&[0u8; 4096]).unwrap_err().to_string();
        assert!(e.contains("NIMBUSNC"), "{e}");
    }

    #[test]
    fn another_seed_or_size_does_not_match() {
        let info = NoiseCacheInfo::parse(&sample()).unwrap();
        let mut other = small();
        other.seed = 2;
        let e = info.check_matches(&other).unwrap_err().to_string();
        assert!(e.contains("seed 1") && e.contains("seed 2"), "{e}");
        other = small();
        other.base_size = 16;
        assert!(info.check_matches(&other).is_err());
        // Sizes that are not in the cache's header do not matter (weather, blue noise).
        other = small();
        other.weather_size = 64;
        other.blue_noise_size = 8;
        info.check_matches(&other).unwrap();
    }

    #[test]
    fn bake_id_follows_the_shader_source() {
        assert_ne!(source_hash(&[("x", "a")]), source_hash(&[("x", "b")]));
        // The id hashes exactly the modules the bake pipeline is built from.
        let pass = crate::gpu::shaders::pass_modules("noise_bake");
        assert_eq!(BAKE_ID, source_hash(pass));
        let mut changed: Vec<(&str, &str)> = pass.to_vec();
        let edited = format!("{} const edited = 1.0;", changed[1].1);
        changed[1].1 = &edited;
        assert_ne!(BAKE_ID, source_hash(&changed));
        // A comment added to a module keeps the id.
        let commented = format!("// a note\n{}\n/* another */", changed[0].1);
        changed = pass.to_vec();
        changed[0].1 = &commented;
        assert_eq!(BAKE_ID, source_hash(&changed));
        let mut bytes = sample();
        bytes[12..16].copy_from_slice(&(BAKE_ID ^ 1).to_le_bytes());
        let e = NoiseCacheInfo::parse(&bytes).unwrap_err().to_string();
        assert!(e.contains("another noise algorithm"), "{e}");
    }

    #[test]
    fn source_hash_reads_tokens_not_comments_or_layout() {
        let id = |text: &str| source_hash(&[("m.wgsl", text)]);
        let code = "fn f(x: f32) -> f32 {\n    return x * 2.0;\n}\n";
        // Comments of both kinds (nested too), indentation, blank lines and line ends: the same.
        for same in [
            "// why f doubles\nfn f(x: f32) -> f32 {\n    return x * 2.0; // twice\n}\n",
            "fn f(x: f32) -> f32 { return x * 2.0; }",
            "\n\n  fn f(x: f32)\t-> f32 {\r\n\r\n return x * 2.0;\n}",
            "fn f(x: f32) -> f32 {\n    return x /* a /* nested */ note */ * 2.0;\n}\n",
            "fn f(x: f32) -> f32 {\n    return x * 2.0;\n}\n/* unterminated at the end",
            // A comment parts two tokens as whitespace does.
            "fn f(x: f32) -> f32 {\n    return/**/x * 2.0;\n}\n",
        ] {
            assert_eq!(id(code), id(same), "{same:?}");
        }
        // Code: a changed token, tokens run together, a division (no comment).
        for other in [
            "fn f(x: f32) -> f32 {\n    return x * 3.0;\n}\n",
            "fn f(x: f32) -> f32 {\n    returnx * 2.0;\n}\n",
            "fn f(x: f32) -> f32 {\n    return x / 2.0;\n}\n",
        ] {
            assert_ne!(id(code), id(other), "{other:?}");
        }
        // Text moved across a module boundary is a change, and so is a module's order.
        let pair = |a: &'static str, b: &'static str| source_hash(&[("a", a), ("b", b)]);
        assert_ne!(pair("x=1;", "y=2;"), pair("x=1;y", "=2;"));
        assert_ne!(pair("x=1;", "y=2;"), pair("y=2;", "x=1;"));
    }
}
