//! Bind groups made once and reused: a frame loop must not create GPU objects per frame.
//!
//! A bind group is keyed by the uniform buffer it binds (one per view of a renderer) and the
//! texture views it binds (wgpu compares both by id). The views of one pass change only on a
//! resize, a settings or weather change, or when the host hands in other textures, and then
//! only between a few known sets (the history ping-pong, the weather slots), so a handful of
//! entries per view and pass is enough. A host that makes new views every frame gets a new
//! bind group every frame: keep your views (the docs say so).

/// How many bind groups one pass keeps per view (its ping-pong and weather-slot variants fit).
const ENTRIES: usize = 6;

type Entry = (Vec<wgpu::TextureView>, wgpu::BindGroup);

/// The bind groups of one pipeline, per owning uniform buffer, keyed by the views they bind.
#[derive(Default)]
pub(crate) struct BindCache {
    /// Per uniform buffer; within each, most recently used last.
    owners: Vec<(wgpu::Buffer, Vec<Entry>)>,
    created: u64,
}

impl BindCache {
    /// The bind group for `owner` and `views` (in binding order, as `make` binds them), made
    /// by `make` only when no cached one binds exactly these.
    pub(crate) fn get(
        &mut self,
        owner: &wgpu::Buffer,
        views: &[&wgpu::TextureView],
        make: impl FnOnce() -> wgpu::BindGroup,
    ) -> wgpu::BindGroup {
        let slot = match self.owners.iter().position(|(b, _)| b == owner) {
            Some(i) => i,
            None => {
                self.owners.push((owner.clone(), Vec::new()));
                self.owners.len() - 1
            }
        };
        let entries = &mut self.owners[slot].1;
        let hit = entries.iter().position(|(key, _)| {
            key.len() == views.len() && key.iter().zip(views).all(|(a, b)| a == *b)
        });
        let entry = match hit {
            Some(i) => entries.remove(i),
            None => {
                if entries.len() == ENTRIES {
                    entries.remove(0);
                }
                self.created += 1;
                (views.iter().map(|v| (*v).clone()).collect(), make())
            }
        };
        let group = entry.1.clone();
        entries.push(entry);
        group
    }

    /// Bind groups made so far.
    pub(crate) fn created(&self) -> u64 {
        self.created
    }

    /// Drops the bind groups of one owner (a view that was resized or destroyed).
    pub(crate) fn forget(&mut self, owner: &wgpu::Buffer) {
        self.owners.retain(|(b, _)| b != owner);
    }

    /// Drops every cached bind group (and with them the references to the views they bind).
    pub(crate) fn clear(&mut self) {
        self.owners.clear();
    }
}
