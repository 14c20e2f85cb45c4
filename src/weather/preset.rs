//! Weather as data: everything that defines a sky's weather, the built-in presets, blending
//! between two weathers, and human-readable preset files (TOML).
//!
//! A [`Weather`] is what a transition blends: every scalar lerps, the weather map is generated
//! from `map` and blended on the GPU. Global look (noise tile sizes, march budget, haze) stays
//! in [`crate::Settings`].

use std::path::Path;

use glam::{Vec2, Vec3};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::validate::{color, count, in_range, invalid, non_negative, positive};

/// Altitudes of the cloud shell (two spheres concentric with the planet).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CloudLayer {
    /// Altitude of the cloud bases in meters. Default 1 500.
    pub bottom_altitude: f32,
    /// Altitude of the highest cloud tops in meters. Default 4 500.
    pub top_altitude: f32,
}

/// The density model's knobs (Schneider, as described in the Aetherius thesis).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CloudShape {
    /// Global coverage in [0, 1], multiplied with the weather map's coverage. 0 = clear sky.
    pub coverage: f32,
    /// Global density multiplier, >= 0.
    pub density: f32,
    /// Extinction coefficient σt (1/m) of density 1 (cumulus: 0.02–0.1).
    pub extinction: f32,
    /// Single-scattering albedo σs/σt in [0, 1]; 1 - albedo is absorbed.
    pub albedo: f32,
    /// How deeply detail noise erodes the base shape, in [0, 1].
    pub detail_strength: f32,
    /// Fraction of the shell over which density fades in at the bottom and out at the top,
    /// in [0, 0.5].
    pub layer_softness: f32,
    /// How steeply density rises from a cloud's eroded edge into its body, in [1, 8]: the
    /// eroded density is multiplied by it and capped at full density. 1 keeps the erosion's
    /// own ramp (soft, cotton-like outlines); 4 makes the ramp a quarter as wide, so the detail
    /// noise carves crisp billows into a body of nearly uniform density. The outline (where
    /// density is 0) does not move.
    pub edge_sharpness: f32,
}

/// One cloud layer of the weather map (a channel: R, G or B).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MapLayer {
    /// How much of this layer's cloud cells survive, in [0, 1]; 0 = layer absent.
    pub amount: f32,
    /// Vertical profile in [0, 1]: 0 stratus, 1/3 stratocumulus, 2/3 cumulus, 1 cumulonimbus.
    pub cloud_type: f32,
    /// Cloud cells across one weather-map tile, in [1, 64].
    pub frequency: u32,
}

/// The procedural weather map: up to three layers, each its own cloud type.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WeatherMap {
    /// Seed of the map's noise.
    pub seed: u32,
    /// One to three layers; where several overlap, the densest wins before detail erosion.
    pub layers: Vec<MapLayer>,
}

/// Wind, in world units, moving the weather map and the noise volumes.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Wind {
    /// Horizontal direction (tangent x, z; normalised on use).
    pub direction: Vec2,
    /// Speed in m/s, >= 0.
    pub speed: f32,
    /// Multiplier of the speed for the weather map (0 holds the cloud field still).
    pub weather_factor: f32,
    /// Multiplier for the base-shape noise.
    pub base_factor: f32,
    /// Multiplier for the detail noise (usually faster: small eddies).
    pub detail_factor: f32,
    /// Shear: how far (m) cloud tops lean downwind relative to their bases.
    pub skew: f32,
}

/// A thin high layer (cirrus-like): a textured sheet at one altitude, usable with any weather.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HighLayer {
    /// Coverage in [0, 1]; 0 = no high layer.
    pub coverage: f32,
    /// Altitude in meters (above the cloud shell).
    pub altitude: f32,
    /// Vertical optical depth of the densest streaks, >= 0.
    pub optical_depth: f32,
}

/// Horizon Zero Dawn's horizon gradient: from a distance on, the weather tends toward big
/// cumulus at a given coverage, so the horizon always has clouds (Schneider 2015).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HorizonGradient {
    /// Strength in [0, 1]; 0 = off.
    pub strength: f32,
    /// Horizontal distance from the camera (m) where the gradient starts.
    pub start_distance: f32,
    /// Coverage reached far away, in [0, 1].
    pub coverage: f32,
    /// Cloud type reached far away, in [0, 1].
    pub cloud_type: f32,
}

/// Everything that defines a weather; a preset is a named `Weather`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Weather {
    /// Display name.
    pub name: String,
    /// Shell altitudes.
    pub layer: CloudLayer,
    /// Density model.
    pub clouds: CloudShape,
    /// Weather-map generator.
    pub map: WeatherMap,
    /// Wind.
    pub wind: Wind,
    /// Ambient radiance at the top of the shell (linear RGB).
    pub ambient_top: Vec3,
    /// Ambient radiance at the bottom of the shell.
    pub ambient_bottom: Vec3,
    /// Cirrus-like high layer.
    pub high_layer: HighLayer,
    /// Horizon gradient (off by default).
    pub horizon: HorizonGradient,
}

impl Default for CloudLayer {
    fn default() -> Self {
        Self {
            bottom_altitude: 1_500.0,
            top_altitude: 4_500.0,
        }
    }
}

impl Default for CloudShape {
    fn default() -> Self {
        Self {
            coverage: 0.4,
            density: 1.0,
            extinction: 0.04,
            // Water droplets absorb almost nothing in the visible (1 - ω ≈ 1e-5 to 1e-4);
            // 0.999 leaves room for haze and soot. With the delta-Eddington model albedo
            // matters in thick clouds as in the path tracer (τ 50: ω 0.999 -> 1 is +32%).
            albedo: 0.999,
            // Eroding the whole depth of the base shape's range lets the detail cells carve
            // the cumuliform base (which rises five times as steeply as before it was
            // stretched: profile.rs, `CARVED_RANGE`) into separate billows; 0.35 left shallow
            // bumps and 0.7 soft dents.
            detail_strength: 1.0,
            layer_softness: 0.1,
            // A ramp a quarter as wide: bodies of nearly uniform density whose eroded edges
            // are crisp cauliflower billows (Schneider 2015's images), where 1 gave soft cotton
            // blobs whose look no march setting changed (issue 11, point 5).
            edge_sharpness: 4.0,
        }
    }
}

impl Default for MapLayer {
    fn default() -> Self {
        Self {
            amount: 1.0,
            cloud_type: 0.62,
            frequency: 10,
        }
    }
}

impl Default for WeatherMap {
    fn default() -> Self {
        Self {
            seed: 3,
            layers: vec![MapLayer::default()],
        }
    }
}

impl Default for Wind {
    fn default() -> Self {
        Self {
            direction: Vec2::X,
            speed: 10.0,
            weather_factor: 1.0,
            base_factor: 1.0,
            detail_factor: 2.0,
            skew: 500.0,
        }
    }
}

impl Default for HighLayer {
    fn default() -> Self {
        Self {
            coverage: 0.0,
            altitude: 9_000.0,
            optical_depth: 0.6,
        }
    }
}

impl Default for HorizonGradient {
    fn default() -> Self {
        Self {
            strength: 0.0,
            start_distance: 15_000.0,
            coverage: 0.5,
            cloud_type: 2.0 / 3.0,
        }
    }
}

impl Default for Weather {
    fn default() -> Self {
        Weather::sparse()
    }
}

/// The built-in presets, by stable id (the C API's `NIMBUS_PRESET_*`; 0 is no preset).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum Preset {
    /// No clouds.
    Clear = 1,
    /// Fair-weather cumulus.
    Sparse = 2,
    /// Cumulus over a broken stratocumulus deck.
    Cloudy = 3,
    /// A closed low deck.
    Overcast = 4,
    /// Towering cumulonimbus over a dark deck.
    Stormy = 5,
}

impl Preset {
    /// Every built-in preset, in id order.
    pub const ALL: [Preset; 5] = [
        Preset::Clear,
        Preset::Sparse,
        Preset::Cloudy,
        Preset::Overcast,
        Preset::Stormy,
    ];

    /// The preset with this id, if any.
    pub fn from_id(id: u32) -> Option<Preset> {
        Preset::ALL.into_iter().find(|p| *p as u32 == id)
    }

    /// The preset's weather.
    pub fn weather(self) -> Weather {
        match self {
            Preset::Clear => Weather::clear(),
            Preset::Sparse => Weather::sparse(),
            Preset::Cloudy => Weather::cloudy(),
            Preset::Overcast => Weather::overcast(),
            Preset::Stormy => Weather::stormy(),
        }
    }
}

fn layer(amount: f32, cloud_type: f32, frequency: u32) -> MapLayer {
    MapLayer {
        amount,
        cloud_type,
        frequency,
    }
}

impl Weather {
    /// No clouds at all: a bright, clear ambient.
    pub fn clear() -> Weather {
        Weather {
            name: "clear".into(),
            clouds: CloudShape {
                coverage: 0.0,
                ..CloudShape::default()
            },
            ..Weather::sparse()
        }
    }

    /// Fair-weather cumulus: small separated heaps with flat bases.
    pub fn sparse() -> Weather {
        Weather {
            name: "sparse".into(),
            layer: CloudLayer::default(),
            clouds: CloudShape::default(),
            map: WeatherMap::default(),
            wind: Wind::default(),
            ambient_top: Vec3::new(0.55, 0.65, 0.85) * 0.35,
            ambient_bottom: Vec3::new(0.45, 0.5, 0.6) * 0.12,
            high_layer: HighLayer::default(),
            horizon: HorizonGradient::default(),
        }
    }

    /// Larger cumulus over a broken stratocumulus deck.
    pub fn cloudy() -> Weather {
        Weather {
            name: "cloudy".into(),
            layer: CloudLayer {
                bottom_altitude: 1_200.0,
                top_altitude: 5_000.0,
            },
            // 0.62 before cumulus were carved by their noise: 0.8 keeps its view from above as
            // cloudy (0.78 of the pixels opaque, 0.78 before; from the ground 0.74, 0.86 before).
            clouds: CloudShape {
                coverage: 0.8,
                density: 1.1,
                ..CloudShape::default()
            },
            map: WeatherMap {
                seed: 11,
                layers: vec![layer(1.0, 0.7, 7), layer(0.75, 0.3, 5)],
            },
            wind: Wind {
                speed: 14.0,
                ..Wind::default()
            },
            ambient_top: Vec3::new(0.5, 0.58, 0.72) * 0.32,
            ambient_bottom: Vec3::new(0.4, 0.43, 0.5) * 0.1,
            ..Weather::sparse()
        }
    }

    /// A closed, low, fairly uniform deck.
    pub fn overcast() -> Weather {
        Weather {
            name: "overcast".into(),
            layer: CloudLayer {
                bottom_altitude: 900.0,
                top_altitude: 3_500.0,
            },
            clouds: CloudShape {
                coverage: 0.97,
                density: 1.2,
                detail_strength: 0.2,
                layer_softness: 0.15,
                // A stratus deck's underside is soft: the cumulus' crisp billows would print
                // its base as a field of hard-edged lumps.
                edge_sharpness: 1.0,
                ..CloudShape::default()
            },
            map: WeatherMap {
                seed: 23,
                layers: vec![layer(1.0, 0.36, 4), layer(1.0, 0.25, 6)],
            },
            wind: Wind {
                speed: 8.0,
                skew: 200.0,
                ..Wind::default()
            },
            ambient_top: Vec3::new(0.45, 0.48, 0.55) * 0.3,
            ambient_bottom: Vec3::new(0.35, 0.36, 0.4) * 0.08,
            ..Weather::sparse()
        }
    }

    /// Towering cumulonimbus rising from a dark stratocumulus deck.
    pub fn stormy() -> Weather {
        Weather {
            name: "stormy".into(),
            layer: CloudLayer {
                bottom_altitude: 700.0,
                top_altitude: 9_000.0,
            },
            // Towers carved by their noise (profile.rs, `CARVED_RANGE`) are thinner where the
            // noise is low: coverage 0.9 (0.8 before) keeps the deck closed. Sharpened edges
            // (`edge_sharpness` 4) fill the towers' bodies to full density, so density 1.0
            // (1.6 with soft edges) gives a dark deck with the towers' darker cores and lighter
            // gaps between them: the contact sheet's ground view has mean 85 of 255 (65 at 1.6;
            // 139 with soft edges, a grey that read as overcast rather than storm).
            clouds: CloudShape {
                coverage: 0.9,
                density: 1.0,
                extinction: 0.05,
                // Storm towers lift dust and soot: a little more absorption than fair cumulus.
                albedo: 0.995,
                detail_strength: 0.4,
                layer_softness: 0.06,
                ..CloudShape::default()
            },
            map: WeatherMap {
                seed: 41,
                layers: vec![layer(1.0, 1.0, 5), layer(0.9, 0.1, 6)],
            },
            wind: Wind {
                speed: 22.0,
                skew: 1_500.0,
                detail_factor: 2.5,
                ..Wind::default()
            },
            ambient_top: Vec3::new(0.38, 0.4, 0.46) * 0.3,
            ambient_bottom: Vec3::new(0.3, 0.31, 0.35) * 0.14,
            ..Weather::sparse()
        }
    }

    /// A typical cirrus veil: 9 km up, 70% coverage.
    pub fn cirrus() -> HighLayer {
        HighLayer {
            coverage: 0.7,
            ..HighLayer::default()
        }
    }

    /// This weather with a cirrus-like high layer added.
    pub fn with_high_layer(mut self, high: HighLayer) -> Weather {
        self.high_layer = high;
        self
    }

    /// This weather with the horizon gradient turned on at full strength.
    pub fn with_horizon_gradient(mut self) -> Weather {
        self.horizon.strength = 1.0;
        self
    }

    /// Checks every field; errors name the field path relative to the weather.
    pub fn validate(&self) -> Result<()> {
        let l = &self.layer;
        non_negative("layer.bottom_altitude", l.bottom_altitude)?;
        positive("layer.top_altitude", l.top_altitude)?;
        if l.bottom_altitude >= l.top_altitude {
            return Err(invalid(
                "layer.bottom_altitude",
                format!(
                    "must be below layer.top_altitude ({} >= {})",
                    l.bottom_altitude, l.top_altitude
                ),
            ));
        }
        let c = &self.clouds;
        in_range("clouds.coverage", c.coverage, 0.0, 1.0)?;
        non_negative("clouds.density", c.density)?;
        positive("clouds.extinction", c.extinction)?;
        in_range("clouds.albedo", c.albedo, 0.0, 1.0)?;
        in_range("clouds.detail_strength", c.detail_strength, 0.0, 1.0)?;
        in_range("clouds.layer_softness", c.layer_softness, 0.0, 0.5)?;
        in_range("clouds.edge_sharpness", c.edge_sharpness, 1.0, 8.0)?;
        if self.map.layers.is_empty() || self.map.layers.len() > 3 {
            return Err(invalid(
                "map.layers",
                format!("must hold 1 to 3 layers, got {}", self.map.layers.len()),
            ));
        }
        for (i, m) in self.map.layers.iter().enumerate() {
            in_range(&format!("map.layers[{i}].amount"), m.amount, 0.0, 1.0)?;
            in_range(
                &format!("map.layers[{i}].cloud_type"),
                m.cloud_type,
                0.0,
                1.0,
            )?;
            count(&format!("map.layers[{i}].frequency"), m.frequency, 1, 64)?;
        }
        let w = &self.wind;
        if !w.direction.is_finite() {
            return Err(invalid(
                "wind.direction",
                format!("must be finite, got {}", w.direction),
            ));
        }
        non_negative("wind.speed", w.speed)?;
        non_negative("wind.weather_factor", w.weather_factor)?;
        non_negative("wind.base_factor", w.base_factor)?;
        non_negative("wind.detail_factor", w.detail_factor)?;
        crate::validate::finite("wind.skew", w.skew)?;
        color("ambient_top", self.ambient_top)?;
        color("ambient_bottom", self.ambient_bottom)?;
        let h = &self.high_layer;
        in_range("high_layer.coverage", h.coverage, 0.0, 1.0)?;
        positive("high_layer.altitude", h.altitude)?;
        non_negative("high_layer.optical_depth", h.optical_depth)?;
        let z = &self.horizon;
        in_range("horizon.strength", z.strength, 0.0, 1.0)?;
        non_negative("horizon.start_distance", z.start_distance)?;
        in_range("horizon.coverage", z.coverage, 0.0, 1.0)?;
        in_range("horizon.cloud_type", z.cloud_type, 0.0, 1.0)?;
        Ok(())
    }

    /// The weather a fraction `t` of the way from `a` to `b`: every scalar lerps; integer and
    /// text fields (seed, frequencies, name) switch at the midpoint. Missing map layers blend
    /// as absent (amount 0).
    pub fn lerp(a: &Weather, b: &Weather, t: f32) -> Weather {
        // The ends are the inputs exactly (no padded layer lists, no rounding).
        if t <= 0.0 {
            return a.clone();
        }
        if t >= 1.0 {
            return b.clone();
        }
        let f = |x: f32, y: f32| x + (y - x) * t;
        let v3 = |x: Vec3, y: Vec3| x.lerp(y, t);
        let n = a.map.layers.len().max(b.map.layers.len());
        let absent = |l: &MapLayer| MapLayer { amount: 0.0, ..*l };
        let layers = (0..n)
            .map(|i| {
                let la = a.map.layers.get(i).copied();
                let lb = b.map.layers.get(i).copied();
                let la = la.unwrap_or_else(|| absent(&lb.unwrap_or_default()));
                let lb = lb.unwrap_or_else(|| absent(&la));
                MapLayer {
                    amount: f(la.amount, lb.amount),
                    cloud_type: f(la.cloud_type, lb.cloud_type),
                    frequency: pick(t, la.frequency, lb.frequency),
                }
            })
            .collect();
        // Wind blends as a velocity, so a turning wind sweeps through the directions between.
        let vel = |w: &Wind| w.direction.normalize_or_zero() * w.speed;
        let v = vel(&a.wind).lerp(vel(&b.wind), t);
        let direction = if v.length() > 1e-6 {
            v.normalize()
        } else {
            pick(t, a.wind.direction, b.wind.direction)
        };
        Weather {
            name: pick(t, a.name.clone(), b.name.clone()),
            layer: CloudLayer {
                bottom_altitude: f(a.layer.bottom_altitude, b.layer.bottom_altitude),
                top_altitude: f(a.layer.top_altitude, b.layer.top_altitude),
            },
            clouds: CloudShape {
                coverage: f(a.clouds.coverage, b.clouds.coverage),
                density: f(a.clouds.density, b.clouds.density),
                extinction: f(a.clouds.extinction, b.clouds.extinction),
                albedo: f(a.clouds.albedo, b.clouds.albedo),
                detail_strength: f(a.clouds.detail_strength, b.clouds.detail_strength),
                layer_softness: f(a.clouds.layer_softness, b.clouds.layer_softness),
                edge_sharpness: f(a.clouds.edge_sharpness, b.clouds.edge_sharpness),
            },
            map: WeatherMap {
                seed: pick(t, a.map.seed, b.map.seed),
                layers,
            },
            wind: Wind {
                direction,
                speed: v.length(),
                weather_factor: f(a.wind.weather_factor, b.wind.weather_factor),
                base_factor: f(a.wind.base_factor, b.wind.base_factor),
                detail_factor: f(a.wind.detail_factor, b.wind.detail_factor),
                skew: f(a.wind.skew, b.wind.skew),
            },
            ambient_top: v3(a.ambient_top, b.ambient_top),
            ambient_bottom: v3(a.ambient_bottom, b.ambient_bottom),
            high_layer: HighLayer {
                coverage: f(a.high_layer.coverage, b.high_layer.coverage),
                altitude: f(a.high_layer.altitude, b.high_layer.altitude),
                optical_depth: f(a.high_layer.optical_depth, b.high_layer.optical_depth),
            },
            horizon: HorizonGradient {
                strength: f(a.horizon.strength, b.horizon.strength),
                start_distance: f(a.horizon.start_distance, b.horizon.start_distance),
                coverage: f(a.horizon.coverage, b.horizon.coverage),
                cloud_type: f(a.horizon.cloud_type, b.horizon.cloud_type),
            },
        }
    }

    /// The weather as a TOML document.
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self)
            .unwrap_or_else(|e| unreachable!("Weather always serialises: {e}"))
    }

    /// Parses and validates a TOML document. `origin` names it in errors (a path, or
    /// `<string>`). Missing fields take the `sparse` preset's values.
    pub fn from_toml(text: &str, origin: &str) -> Result<Weather> {
        let file_error = |message: String| Error::PresetFile {
            origin: origin.to_string(),
            line: None,
            field: None,
            message,
        };
        if text.len() > MAX_PRESET_BYTES {
            return Err(file_error(format!(
                "is {} bytes; a preset is at most {MAX_PRESET_BYTES} bytes",
                text.len()
            )));
        }
        // An empty (or comment-only) file would silently be the sparse preset: say so instead.
        let has_content = text.lines().any(|l| {
            let l = l.trim();
            !l.is_empty() && !l.starts_with('#')
        });
        if !has_content {
            return Err(file_error(
                "holds no settings (empty or only comments); a preset file sets at least one \
                 field, missing ones take the sparse preset's values (write a built-in preset \
                 out as a template to start from)"
                    .into(),
            ));
        }
        let weather: Weather = toml::from_str(text).map_err(|e| {
            let line = e.span().map(|s| line_of(text, s.start));
            Error::PresetFile {
                origin: origin.to_string(),
                line,
                field: line.and_then(|l| key_on_line(text, l)),
                message: plain_schema_words(e.message().trim()),
            }
        })?;
        weather.validate().map_err(|e| match e {
            Error::InvalidSettings { field, reason } => Error::PresetFile {
                origin: origin.to_string(),
                line: locate(text, &field),
                field: Some(field),
                message: reason,
            },
            other => other,
        })?;
        Ok(weather)
    }

    /// Reads a preset file (at most [`MAX_PRESET_BYTES`]; a larger file, or a device such as
    /// `/dev/zero`, is refused without reading it all).
    pub fn load(path: &Path) -> Result<Weather> {
        use std::io::Read;
        let origin = path.display().to_string();
        let file_error = |message: String| Error::PresetFile {
            origin: origin.clone(),
            line: None,
            field: None,
            message,
        };
        let file = std::fs::File::open(path).map_err(|e| file_error(e.to_string()))?;
        let mut bytes = Vec::new();
        file.take(MAX_PRESET_BYTES as u64 + 1)
            .read_to_end(&mut bytes)
            .map_err(|e| file_error(e.to_string()))?;
        if bytes.len() > MAX_PRESET_BYTES {
            return Err(file_error(format!(
                "is larger than {MAX_PRESET_BYTES} bytes, the most a preset may hold"
            )));
        }
        let text = String::from_utf8(bytes)
            .map_err(|_| file_error("is not UTF-8 text (a preset is a TOML file)".into()))?;
        Weather::from_toml(&text, &origin)
    }

    /// Writes a preset file (validated first, so only loadable files are written).
    pub fn save(&self, path: &Path) -> Result<()> {
        self.validate()?;
        std::fs::write(path, self.to_toml()).map_err(|e| Error::PresetFile {
            origin: path.display().to_string(),
            line: None,
            field: None,
            message: e.to_string(),
        })
    }
}

/// Largest preset accepted, in bytes: a preset is a few hundred bytes; this bounds what a
/// wrong path (a log file, `/dev/zero`) can make Nimbus read.
pub const MAX_PRESET_BYTES: usize = 64 * 1024;

/// The TOML parser names the Rust types it fills ("expected struct CloudLayer"); a preset's
/// author knows tables and arrays.
fn plain_schema_words(message: &str) -> String {
    let mut out = String::with_capacity(message.len());
    let mut rest = message;
    while let Some(at) = rest.find("struct ") {
        out.push_str(&rest[..at]);
        let after = &rest[at + "struct ".len()..];
        let name_len = after
            .find(|c: char| !c.is_alphanumeric() && c != '_')
            .unwrap_or(after.len());
        out.push_str("a table");
        rest = &after[name_len..];
    }
    out.push_str(rest);
    out.replace("a sequence", "an array")
        .replace("a map", "a table")
}

/// The nearer end of a blend, for fields that cannot be interpolated.
fn pick<T>(t: f32, a: T, b: T) -> T {
    if t < 0.5 {
        a
    } else {
        b
    }
}

fn line_of(text: &str, byte: usize) -> usize {
    text[..byte.min(text.len())].matches('\n').count() + 1
}

/// `table.key` for the key assigned on 1-based `line`, from the table header above it.
fn key_on_line(text: &str, line: usize) -> Option<String> {
    let mut table = String::new();
    for (i, l) in text.lines().enumerate() {
        let t = l.trim();
        if t.starts_with('[') {
            table = t.trim_matches(|c| c == '[' || c == ']').trim().to_string();
        }
        if i + 1 == line {
            let key = t.split('=').next()?.trim();
            if key.is_empty() || t.starts_with('[') {
                return (!table.is_empty()).then_some(table);
            }
            return Some(if table.is_empty() {
                key.to_string()
            } else {
                format!("{table}.{key}")
            });
        }
    }
    None
}

/// The 1-based line where a validated field path (`clouds.coverage`,
/// `map.layers[1].amount`) is assigned, if the document spells it out.
fn locate(text: &str, path: &str) -> Option<usize> {
    let (table_path, key) = path.rsplit_once('.').unwrap_or(("", path));
    let (table, index) = match table_path.split_once('[') {
        Some((t, rest)) => (t, rest.trim_end_matches(']').parse::<usize>().ok()),
        None => (table_path, None),
    };
    let mut current = String::new();
    let mut occurrence: isize = -1;
    for (i, l) in text.lines().enumerate() {
        let t = l.trim();
        if t.starts_with('[') {
            current = t.trim_matches(|c| c == '[' || c == ']').trim().to_string();
            if current == table && t.starts_with("[[") {
                occurrence += 1;
            }
            continue;
        }
        let in_table = current == table && index.is_none_or(|k| occurrence == k as isize);
        if in_table && t.split('=').next().map(str::trim) == Some(key) && t.contains('=') {
            return Some(i + 1);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtins_are_valid_and_distinct() {
        for p in Preset::ALL {
            let w = p.weather();
            w.validate().unwrap_or_else(|e| panic!("{p:?}: {e}"));
            assert_eq!(Preset::from_id(p as u32), Some(p));
        }
        assert_eq!(Preset::from_id(99), None);
        for (i, a) in Preset::ALL.iter().enumerate() {
            for b in &Preset::ALL[i + 1..] {
                assert_ne!(a.weather(), b.weather(), "{a:?} == {b:?}");
            }
        }
        Weather::stormy()
            .with_high_layer(HighLayer {
                coverage: 0.6,
                ..HighLayer::default()
            })
            .validate()
            .unwrap();
    }

    #[test]
    fn empty_huge_and_endless_files_are_refused_with_a_reason() {
        for text in ["", "\n\n", "# just a comment\n  # another\n"] {
            let e = Weather::from_toml(text, "<string>")
                .unwrap_err()
                .to_string();
            assert!(e.contains("holds no settings"), "{e}");
        }
        let huge = format!("name = \"x\"\n{}", "# padding\n".repeat(10_000));
        let e = Weather::from_toml(&huge, "<string>")
            .unwrap_err()
            .to_string();
        assert!(e.contains("at most"), "{e}");
        // /dev/zero would be read until memory runs out without the limit.
        if Path::new("/dev/zero").exists() {
            let e = Weather::load(Path::new("/dev/zero"))
                .unwrap_err()
                .to_string();
            assert!(e.contains("larger than"), "{e}");
        }
    }

    #[test]
    fn parse_errors_speak_of_tables_not_rust_structs() {
        let e = Weather::from_toml("[clouds]\ncoverage = 0.5\n[[map.layers]]\n", "<string>");
        let text = format!("{e:?}");
        let e = Weather::from_toml("clouds = 3\n", "<string>")
            .unwrap_err()
            .to_string();
        assert!(!e.contains("struct"), "{e} / {text}");
        assert!(e.contains("table"), "{e}");
    }

    #[test]
    fn lerp_ends_are_the_inputs() {
        let (a, b) = (Weather::sparse(), Weather::stormy());
        assert_eq!(Weather::lerp(&a, &b, 1.0).clouds, b.clouds);
        assert_eq!(Weather::lerp(&a, &b, 0.0).clouds, a.clouds);
        let mid = Weather::lerp(&a, &b, 0.5);
        assert!((mid.clouds.coverage - 0.5 * (a.clouds.coverage + b.clouds.coverage)).abs() < 1e-6);
        // sparse has one layer, stormy two: the missing one blends in from nothing.
        assert_eq!(Weather::lerp(&a, &b, 0.0), a);
        assert!(Weather::lerp(&a, &b, 1e-3).map.layers[1].amount < 1e-2);
        assert!((mid.map.layers[1].amount - 0.45).abs() < 1e-6);
        mid.validate().unwrap();
    }

    #[test]
    fn files_round_trip() {
        for p in Preset::ALL {
            let w = p.weather().with_high_layer(HighLayer {
                coverage: 0.4,
                ..HighLayer::default()
            });
            let text = w.to_toml();
            assert_eq!(Weather::from_toml(&text, "<string>").unwrap(), w, "{text}");
        }
        let dir = std::env::temp_dir().join(format!("nimbus-preset-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("stormy.toml");
        Weather::stormy().save(&path).unwrap();
        assert_eq!(Weather::load(&path).unwrap(), Weather::stormy());
    }

    fn file_error(text: &str) -> (Option<usize>, Option<String>, String) {
        match Weather::from_toml(text, "test.toml") {
            Err(Error::PresetFile {
                line,
                field,
                message,
                ..
            }) => (line, field, message),
            other => panic!("expected a preset file error, got {other:?}"),
        }
    }

    #[test]
    fn bad_files_name_line_and_field() {
        let (line, field, msg) = file_error("name = \"x\"\n[clouds]\ncoverage = 1.5\n");
        assert_eq!(
            (line, field.as_deref()),
            (Some(3), Some("clouds.coverage")),
            "{msg}"
        );
        let (line, field, msg) = file_error("[clouds]\ndensity = 1.0\ncovrage = 0.5\n");
        assert_eq!(line, Some(3), "{msg}");
        assert!(msg.contains("covrage"), "{msg}");
        assert_eq!(field.as_deref(), Some("clouds.covrage"));
        let (line, field, _) = file_error("[clouds]\ncoverage = \"lots\"\n");
        assert_eq!((line, field.as_deref()), (Some(2), Some("clouds.coverage")));
        let (line, _, _) = file_error("[clouds\ncoverage = 0.5\n");
        assert_eq!(line, Some(1));
        let text = "[[map.layers]]\namount = 1.0\n[[map.layers]]\namount = 0.5\ncloud_type = 7.0\n";
        let (line, field, _) = file_error(text);
        assert_eq!(
            (line, field.as_deref()),
            (Some(5), Some("map.layers[1].cloud_type"))
        );
        for bad in ["0.5", "9.0", "nan"] {
            let (line, field, msg) = file_error(&format!("[clouds]\nedge_sharpness = {bad}\n"));
            assert_eq!(
                (line, field.as_deref()),
                (Some(2), Some("clouds.edge_sharpness")),
                "{bad}: {msg}"
            );
        }
        let (_, field, msg) =
            file_error("[layer]\nbottom_altitude = 5000.0\ntop_altitude = 1000.0\n");
        assert_eq!(field.as_deref(), Some("layer.bottom_altitude"), "{msg}");
        let e = Weather::load(Path::new("/nonexistent/nimbus.toml")).unwrap_err();
        assert!(e.to_string().contains("/nonexistent/nimbus.toml"), "{e}");
    }

    #[test]
    fn a_partial_file_fills_in_defaults() {
        let w =
            Weather::from_toml("name = \"mine\"\n[clouds]\ncoverage = 0.2\n", "<string>").unwrap();
        assert_eq!(w.clouds.coverage, 0.2);
        assert_eq!(w.clouds.density, Weather::sparse().clouds.density);
        assert_eq!(w.name, "mine");
    }
}
