//! The fuzz targets' input reader: little-endian values off the input, zeros once it runs out.

pub struct Bytes<'a>(pub &'a [u8]);

impl Bytes<'_> {
    pub fn u32(&mut self) -> u32 {
        let mut b = [0u8; 4];
        let n = self.0.len().min(4);
        b[..n].copy_from_slice(&self.0[..n]);
        self.0 = &self.0[n..];
        u32::from_le_bytes(b)
    }

    /// A value in 0..n.
    pub fn small(&mut self, n: u32) -> u32 {
        self.u32() % n
    }
}
