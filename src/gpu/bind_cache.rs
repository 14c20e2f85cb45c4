//! Bind groups made once and reused: a frame loop must not create GPU objects per frame.
//!
//! A bind group is keyed by the texture views it binds (wgpu compares views by id). The views
//! of one pass change only on a resize, a settings or weather change, or when the host hands
//! in other textures, and then only between a few known sets (the history ping-pong, the
//! weather slots), so a handful of entries per pass is enough. A host that makes new views
//! every frame gets a new bind group every frame: keep your views (the docs say so).

/// How many bind groups one pass keeps (its ping-pong and weather-slot variants fit).
const ENTRIES: usize = 6;

/// The bind groups of one pipeline, keyed by the views they bind.
#[derive(Default)]
pub(crate) struct BindCache {
    /// Most recently used last.
    entries: Vec<(Vec<wgpu::TextureView>, wgpu::BindGroup)>,
    created: u64,
}

impl BindCache {
    /// The bind group for `views` (in binding order, as `make` binds them), made by `make`
    /// only when no cached one binds exactly these views.
    pub(crate) fn get(
        &mut self,
        views: &[&wgpu::TextureView],
        make: impl FnOnce() -> wgpu::BindGroup,
    ) -> wgpu::BindGroup {
        let hit = self.entries.iter().position(|(key, _)| {
            key.len() == views.len() && key.iter().zip(views).all(|(a, b)| a == *b)
        });
        let entry = match hit {
            Some(i) => self.entries.remove(i),
            None => {
                if self.entries.len() == ENTRIES {
                    self.entries.remove(0);
                }
                self.created += 1;
                (views.iter().map(|v| (*v).clone()).collect(), make())
            }
        };
        let group = entry.1.clone();
        self.entries.push(entry);
        group
    }

    /// Bind groups made so far.
    pub(crate) fn created(&self) -> u64 {
        self.created
    }

    /// Drops every cached bind group (and with them the references to the views they bind).
    pub(crate) fn clear(&mut self) {
        self.entries.clear();
    }
}
