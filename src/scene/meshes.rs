//! Meshes kept across the frames of a run. A canonical object's mesh depends on the object
//! alone (its shape, placement and tessellation), not on the camera, so a run of frames
//! (a sequence, a benchmark, the rows of a sweep) tessellates an object once: the next
//! frame whose object is equal to it, field by field, gets the same mesh again. The meshes
//! are the ones [`tessellate`] makes, so the primitives are the same bit for bit.

use super::{Mesh, Object, tessellate};
use crate::fnv::fnv1a;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// Meshes kept at most; when more are made the cache starts afresh (a run whose objects
/// change every frame keeps no more than this).
const KEEP: usize = 1024;

/// The meshes of the canonical objects met so far, by a hash of the object and then by
/// equality (a hash collision only costs a tessellation).
#[derive(Debug, Default)]
pub struct MeshCache {
    kept: Mutex<HashMap<u64, Vec<Kept>>>,
}

/// An object and its mesh.
type Kept = (Object, Arc<Mesh>);

impl MeshCache {
    /// An empty cache.
    pub fn new() -> Self {
        Self::default()
    }

    /// The mesh of `object` (`None` for a raw primitive): a kept one when an equal object
    /// was tessellated before, else a new one, kept.
    pub fn mesh(&self, object: &Object) -> Option<Arc<Mesh>> {
        let key = serde_json::to_vec(object).map_or(0, |b| fnv1a(&b));
        let mut kept = self.kept.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(m) = kept
            .get(&key)
            .and_then(|l| l.iter().find(|(o, _)| o == object))
        {
            return Some(m.1.clone());
        }
        let mesh = Arc::new(tessellate(object)?);
        if kept.values().map(Vec::len).sum::<usize>() >= KEEP {
            kept.clear();
        }
        kept.entry(key)
            .or_default()
            .push((object.clone(), mesh.clone()));
        Some(mesh)
    }

    /// Meshes kept.
    pub fn len(&self) -> usize {
        let kept = self.kept.lock().unwrap_or_else(|e| e.into_inner());
        kept.values().map(Vec::len).sum()
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
    /// its own.
    #[test]
    fn kept_meshes_are_those_of_their_objects() {
        let scene = Scene::embedded("default").expect("embedded scene");
        let cache = MeshCache::new();
        for _ in 0..2 {
            for o in &scene.objects {
                let m = cache
                    .mesh(o)
                    .expect("the default scene's objects are canonical");
                assert_eq!(*m, tessellate(o).expect("canonical"));
            }
        }
        assert_eq!(cache.len(), scene.objects.len());
        let mut moved = scene.objects[0].clone();
        if let Object::Cone { tessellation, .. } = &mut moved {
            *tessellation += 1;
        } else {
            panic!("the default scene's first object is a cone");
        }
        let m = cache.mesh(&moved).expect("canonical");
        assert_eq!(*m, tessellate(&moved).expect("canonical"));
        assert_ne!(*m, *cache.mesh(&scene.objects[0]).expect("canonical"));
        assert_eq!(cache.len(), scene.objects.len() + 1);
    }
}
