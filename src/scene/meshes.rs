//! Meshes kept across the frames of a run. A canonical object's mesh depends on the object
//! alone (its shape, placement and tessellation), not on the camera, so a run of frames
//! (a sequence, a benchmark, the rows of a sweep) tessellates an object once: the next
//! frame whose object is equal to it, field by field, gets the same mesh again. The meshes
//! are the ones [`tessellate`] makes, so the primitives are the same bit for bit. Only the
//! meshes of the frame being made and of the one before are kept, so a run whose objects
//! move every frame holds two frames' meshes at most.

use super::{Mesh, Object, tessellate};
use crate::fnv::fnv1a;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// Objects and their meshes by a hash of the object (then found by equality: a hash
/// collision only costs a tessellation).
type Kept = HashMap<u64, Vec<(Object, Arc<Mesh>)>>;

/// The meshes of the canonical objects of this frame and of the frame before.
#[derive(Debug, Default)]
pub struct MeshCache {
    /// This frame's and the last frame's.
    kept: Mutex<(Kept, Kept)>,
}

impl MeshCache {
    /// An empty cache.
    pub fn new() -> Self {
        Self::default()
    }

    /// Starts a frame: the meshes of the frame before are dropped unless this frame meets
    /// their objects again.
    pub fn next_frame(&self) {
        let mut kept = self.kept.lock().unwrap_or_else(|e| e.into_inner());
        let (now, before) = &mut *kept;
        *before = std::mem::take(now);
    }

    /// The mesh of `object` (`None` for a raw primitive): the kept one when an equal object
    /// was tessellated in this frame or the one before, else a new one, kept.
    pub fn mesh(&self, object: &Object) -> Option<Arc<Mesh>> {
        let key = serde_json::to_vec(object).map_or(0, |b| fnv1a(&b));
        let mut kept = self.kept.lock().unwrap_or_else(|e| e.into_inner());
        let (now, before) = &mut *kept;
        if let Some((_, m)) = now
            .get(&key)
            .and_then(|l| l.iter().find(|(o, _)| o == object))
        {
            return Some(m.clone());
        }
        // The frame before's mesh moves to this frame's.
        let old = before.get_mut(&key).and_then(|l| {
            let at = l.iter().position(|(o, _)| o == object)?;
            Some(l.swap_remove(at).1)
        });
        let mesh = match old {
            Some(m) => m,
            None => Arc::new(tessellate(object)?),
        };
        now.entry(key)
            .or_default()
            .push((object.clone(), mesh.clone()));
        Some(mesh)
    }

    /// Meshes kept.
    pub fn len(&self) -> usize {
        let kept = self.kept.lock().unwrap_or_else(|e| e.into_inner());
        let count = |k: &Kept| k.values().map(Vec::len).sum::<usize>();
        count(&kept.0) + count(&kept.1)
    }

    /// Whether no mesh is kept.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;

    /// A kept mesh is the one tessellation makes; an object that differs in one field gets
    /// its own; a mesh not met again in the next frame is dropped after it.
    #[test]
    fn kept_meshes_are_those_of_their_objects() {
        let scene = Scene::embedded("default").expect("embedded scene");
        let n = scene.objects.len();
        let cache = MeshCache::new();
        for _ in 0..2 {
            cache.next_frame();
            for o in &scene.objects {
                let m = cache
                    .mesh(o)
                    .expect("the default scene's objects are canonical");
                assert_eq!(*m, tessellate(o).expect("canonical"));
            }
            // The second frame's meshes are the first's, moved.
            assert_eq!(cache.len(), n);
        }
        let mut moved = scene.objects[0].clone();
        if let Object::Cone { tessellation, .. } = &mut moved {
            *tessellation += 1;
        } else {
            panic!("the default scene's first object is a cone");
        }
        // A frame with the cone changed: it gets its own mesh; the old cone's stays the
        // last frame's.
        cache.next_frame();
        let m = cache.mesh(&moved).expect("canonical");
        assert_eq!(*m, tessellate(&moved).expect("canonical"));
        for o in &scene.objects[1..] {
            cache.mesh(o);
        }
        assert_eq!(cache.len(), n + 1);
        // The next frame drops the old cone's mesh, which it does not meet.
        cache.next_frame();
        assert_eq!(cache.len(), n);
        assert_ne!(*m, *cache.mesh(&scene.objects[0]).expect("canonical"));
    }
}
