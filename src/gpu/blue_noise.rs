//! Blue noise for the march jitter, generated once at init on the CPU by Ulichney's
//! void-and-cluster method (1993) on a torus, with a windowed Gaussian energy (σ = 1.5).

const SIGMA: f32 = 1.5;
const RADIUS: i32 = 6;

struct Field {
    n: usize,
    bits: Vec<bool>,
    energy: Vec<f32>,
    kernel: Vec<f32>,
}

impl Field {
    fn new(n: usize) -> Self {
        let side = (2 * RADIUS + 1) as usize;
        let mut kernel = Vec::with_capacity(side * side);
        for dy in -RADIUS..=RADIUS {
            for dx in -RADIUS..=RADIUS {
                kernel.push((-((dx * dx + dy * dy) as f32) / (2.0 * SIGMA * SIGMA)).exp());
            }
        }
        Self {
            n,
            bits: vec![false; n * n],
            energy: vec![0.0; n * n],
            kernel,
        }
    }

    fn toggle(&mut self, i: usize, on: bool) {
        self.bits[i] = on;
        let sign = if on { 1.0 } else { -1.0 };
        let (n, x0, y0) = (self.n as i32, (i % self.n) as i32, (i / self.n) as i32);
        let side = 2 * RADIUS + 1;
        for dy in -RADIUS..=RADIUS {
            for dx in -RADIUS..=RADIUS {
                let x = (x0 + dx).rem_euclid(n) as usize;
                let y = (y0 + dy).rem_euclid(n) as usize;
                let k = ((dy + RADIUS) * side + dx + RADIUS) as usize;
                self.energy[y * self.n + x] += sign * self.kernel[k];
            }
        }
    }

    /// The set pixel with the highest energy (tightest cluster).
    fn tightest_cluster(&self) -> usize {
        (0..self.bits.len())
            .filter(|&i| self.bits[i])
            .max_by(|&a, &b| self.energy[a].total_cmp(&self.energy[b]))
            .unwrap_or(0)
    }

    /// The empty pixel with the lowest energy (largest void).
    fn largest_void(&self) -> usize {
        (0..self.bits.len())
            .filter(|&i| !self.bits[i])
            .min_by(|&a, &b| self.energy[a].total_cmp(&self.energy[b]))
            .unwrap_or(0)
    }
}

/// A `size`×`size` blue-noise threshold map: every byte value is equally frequent and
/// neighbours are anti-correlated. Deterministic for a given seed.
pub(crate) fn generate(size: u32, seed: u32) -> Vec<u8> {
    let n = size as usize;
    let count = n * n;
    let mut field = Field::new(n);
    // Initial random pattern of ~10% minority pixels (xorshift, seeded).
    let mut state = seed.wrapping_mul(0x9E37_79B9) | 1;
    let mut rand = move || {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        state
    };
    let ones = (count / 10).max(1);
    let mut placed = 0;
    while placed < ones {
        let i = rand() as usize % count;
        if !field.bits[i] {
            field.toggle(i, true);
            placed += 1;
        }
    }
    // Relax into a well-spread initial pattern: move the tightest cluster to the largest void.
    for _ in 0..count {
        let c = field.tightest_cluster();
        field.toggle(c, false);
        let v = field.largest_void();
        if v == c {
            field.toggle(c, true);
            break;
        }
        field.toggle(v, true);
    }
    let initial: Vec<bool> = field.bits.clone();
    let mut rank = vec![0usize; count];
    // Phase 1: rank the initial pattern by removing tightest clusters.
    let mut k = ones;
    while k > 0 {
        let c = field.tightest_cluster();
        field.toggle(c, false);
        k -= 1;
        rank[c] = k;
    }
    // Phases 2 and 3: restore the pattern, then fill the largest voids in order.
    for (i, &on) in initial.iter().enumerate() {
        if on {
            field.toggle(i, true);
        }
    }
    for r in ones..count {
        let v = field.largest_void();
        field.toggle(v, true);
        rank[v] = r;
    }
    rank.iter().map(|&r| ((r * 256) / count) as u8).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_value_is_equally_frequent() {
        let bn = generate(32, 3);
        let mut hist = [0u32; 256];
        for v in &bn {
            hist[*v as usize] += 1;
        }
        assert!(hist.iter().all(|&h| h == 4), "{hist:?}");
    }

    #[test]
    fn neighbours_are_anticorrelated_unlike_white_noise() {
        let n = 32usize;
        let bn = generate(n as u32, 5);
        let mut diff = 0.0f64;
        for y in 0..n {
            for x in 0..n {
                let a = bn[y * n + x] as f64 / 255.0;
                let b = bn[y * n + (x + 1) % n] as f64 / 255.0;
                diff += (a - b).abs();
            }
        }
        let mean = diff / (n * n) as f64;
        // Uniform white noise gives E|a - b| = 1/3.
        assert!(mean > 0.4, "mean neighbour difference {mean}");
    }

    #[test]
    fn seeded_and_deterministic() {
        assert_eq!(generate(16, 9), generate(16, 9));
        assert_ne!(generate(16, 9), generate(16, 10));
    }
}
