//! The noise cache: a renderer started from an exported cache holds the same volumes (every
//! mip, byte for byte) and renders the same picture as one that baked them; unusable caches
//! are refused with their reason, or ignored under `CacheOrBake`; a re-bake forgets the cache.

mod common;
use common::{quiet, setup, small_noise, H, W};

use nimbus::demo::standard_views;
use nimbus::noise_cache::{cache_bytes, NoiseCacheInfo};
use nimbus::{Error, Headless, NoiseStart, NoiseVolume, Settings};

fn start(settings: Settings, noise: NoiseStart<'_>) -> nimbus::Result<Headless> {
    setup();
    let mut h = Headless::with_noise(settings, noise)?;
    h.resize(W, H)?;
    Ok(h)
}

fn volumes(h: &Headless) -> Vec<Vec<u8>> {
    let mut all = Vec::new();
    for (which, edge) in [(NoiseVolume::Base, 32u32), (NoiseVolume::Detail, 16)] {
        for mip in 0..=edge.ilog2() {
            all.push(h.read_noise(which, mip).unwrap());
        }
    }
    all
}

#[test]
fn a_cached_start_matches_a_bake_texel_for_texel_and_pixel_for_pixel() {
    let settings = quiet(small_noise(5));
    let mut baked = start(settings.clone(), NoiseStart::Bake).unwrap();
    assert!(!baked.renderer().noise_from_cache());
    let cache = baked.renderer().export_noise_cache().unwrap();
    assert_eq!(Some(cache.len()), cache_bytes(32, 16));
    let info = NoiseCacheInfo::parse(&cache).unwrap();
    assert_eq!((info.seed, info.base_size, info.detail_size), (5, 32, 16));

    let mut cached = start(settings, NoiseStart::Cache(&cache)).unwrap();
    assert!(cached.renderer().noise_from_cache());
    let (a, b) = (volumes(&baked), volumes(&cached));
    assert_eq!(a.len(), 6 + 5);
    for (level, (a, b)) in a.iter().zip(&b).enumerate() {
        assert!(a == b, "volume level {level} differs");
    }
    // Not a trivially equal pair: the noise has structure.
    assert!(a[0].iter().any(|&v| v != a[0][0]));

    let frame = standard_views()[0].frame(W, H, 2.0);
    baked.render(&frame).unwrap();
    cached.render(&frame).unwrap();
    assert_eq!(baked.read_output().unwrap(), cached.read_output().unwrap());
    // An export of the cached renderer is the same cache.
    assert!(cached.renderer().export_noise_cache().unwrap() == cache);
}

#[test]
fn unusable_caches_are_refused_or_ignored_on_request() {
    let settings = small_noise(5);
    let baked = start(settings.clone(), NoiseStart::Bake).unwrap();
    let cache = baked.renderer().export_noise_cache().unwrap();
    drop(baked);

    let refused = |s: Settings, bytes: &[u8], needle: &str| match start(s, NoiseStart::Cache(bytes))
    {
        Err(Error::NoiseCache(m)) => assert!(m.contains(needle), "{m}"),
        Err(e) => panic!("expected a noise cache error, got {e}"),
        Ok(_) => panic!("accepted a cache that should fail ({needle})"),
    };
    refused(small_noise(6), &cache, "seed 6");
    let mut bigger = settings.clone();
    bigger.noise.base_size = 64;
    refused(bigger, &cache, "base 64");
    let mut damaged = cache.clone();
    damaged[cache.len() / 2] ^= 0x40;
    refused(settings.clone(), &damaged, "checksum");
    refused(settings.clone(), &cache[..cache.len() - 3], "truncated");
    refused(
        settings.clone(),
        b"not a cache at all, but long enough for a header....",
        "NIMBUSNC",
    );

    // CacheOrBake: the right cache is used, a wrong one is ignored and the volumes baked.
    let used = start(settings.clone(), NoiseStart::CacheOrBake(&cache)).unwrap();
    assert!(used.renderer().noise_from_cache());
    let ignored = start(small_noise(6), NoiseStart::CacheOrBake(&cache)).unwrap();
    assert!(!ignored.renderer().noise_from_cache());
    let fresh = start(small_noise(6), NoiseStart::Bake).unwrap();
    assert!(volumes(&ignored)[0] == volumes(&fresh)[0]);

    // A settings change that re-bakes forgets the cache; one that does not keeps it.
    let mut used = used;
    let mut s = used.renderer().settings().clone();
    s.noise.base_scale *= 2.0;
    used.renderer_mut().set_settings(s.clone()).unwrap();
    assert!(used.renderer().noise_from_cache());
    s.noise.seed = 9;
    used.renderer_mut().set_settings(s).unwrap();
    assert!(!used.renderer().noise_from_cache());
}
