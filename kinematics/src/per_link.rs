//! Geometry derived from every link of a model (sphere covers, distance fields), computed
//! once per model on all cores, and once per process for the built-in robots.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use crate::model::{LinkShape, RobotModel};

/// Per-link values already computed for built-in models: source name, fingerprint, values.
pub(crate) type BuiltinCache<T> = Mutex<Vec<(String, u64, Arc<Vec<T>>)>>;

/// `derive` applied to every link's collision shape (`T::default()` for a link without one).
///
/// Links are independent, so they are computed on every core at once, each thread taking the
/// next link not yet taken; a value depends only on its link, so the result does not depend
/// on the threads. For a built-in robot the values are kept in `cache` and shared by every
/// model loaded from the same embedded text.
pub(crate) fn per_link<T, F>(model: &RobotModel, cache: &'static BuiltinCache<T>, derive: F) -> Arc<Vec<T>>
where
    T: Default + Send + Sync,
    F: Fn(&LinkShape) -> T + Sync,
{
    let compute = || {
        let n = model.links().len();
        let threads = std::thread::available_parallelism()
            .map_or(1, |t| t.get())
            .min(n.max(1));
        let next = AtomicUsize::new(0);
        let mut out: Vec<T> = (0..n).map(|_| T::default()).collect();
        std::thread::scope(|scope| {
            let workers: Vec<_> = (0..threads)
                .map(|_| {
                    scope.spawn(|| {
                        let mut done = Vec::new();
                        loop {
                            let l = next.fetch_add(1, Ordering::Relaxed);
                            if l >= n {
                                return done;
                            }
                            done.push((l, model.link_shape(l).map(&derive).unwrap_or_default()));
                        }
                    })
                })
                .collect();
            for worker in workers {
                for (l, value) in worker.join().expect("a per-link thread panicked") {
                    out[l] = value;
                }
            }
        });
        Arc::new(out)
    };
    if !model.source_name().starts_with("builtin:") {
        return compute();
    }
    let key = (model.source_name(), model.fingerprint());
    let mut cache = cache.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    if let Some((_, _, c)) = cache.iter().find(|(n, f, _)| (n.as_str(), *f) == key) {
        return c.clone();
    }
    let c = compute();
    cache.push((key.0.to_owned(), key.1, c.clone()));
    c
}
