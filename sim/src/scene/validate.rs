//! Validation of scene files: finite numbers, names, known categories and variants, joints,
//! supports, and objects that neither overlap each other nor reach into walls.

use std::collections::hash_map::Entry;
use std::collections::{HashMap, HashSet};

use super::footprint::Footprint;
use super::{SceneError, SceneFile, SceneObject};
use crate::assets::{Asset, AssetSpec, Category, Placement};

/// Penetration tolerated between objects and between objects and walls, metres.
///
/// ```
/// use hearth_sim::scene::{OVERLAP_TOLERANCE, SceneFile, SceneObject};
/// let mut s = SceneFile::empty("two stools");
/// s.objects.push(SceneObject::new("a", "chair", 1, [0.0, 0.0, 0.0]));
/// s.objects.push(SceneObject::new("b", "chair", 1, [0.4 - OVERLAP_TOLERANCE / 2.0, 0.0, 0.0]));
/// assert!(s.validate().is_ok()); // they touch by less than the tolerance
/// ```
pub const OVERLAP_TOLERANCE: f64 = 0.01;

fn finite(field: impl FnOnce() -> String, values: &[f64]) -> Result<(), SceneError> {
    match values.iter().find(|v| !v.is_finite()) {
        Some(&value) => Err(SceneError::NonFinite { field: field(), value }),
        None => Ok(()),
    }
}

fn positive(field: impl FnOnce() -> String, value: f64) -> Result<(), SceneError> {
    if value > 0.0 {
        Ok(())
    } else {
        Err(SceneError::invalid(field(), format!("{value} is not positive")))
    }
}

fn unique<'a>(kind: &'static str, names: impl Iterator<Item = &'a str>) -> Result<(), SceneError> {
    let mut seen = HashSet::new();
    for n in names {
        if !seen.insert(n) {
            return Err(SceneError::DuplicateName {
                kind,
                name: n.to_owned(),
            });
        }
    }
    Ok(())
}

/// Builds assets for specs, reusing identical ones.
#[derive(Default)]
pub(crate) struct AssetCache {
    built: HashMap<(Category, usize, u64, Option<crate::assets::Material>), Asset>,
}

impl AssetCache {
    pub(crate) fn get(&mut self, spec: &AssetSpec) -> Result<&Asset, crate::assets::AssetError> {
        let key = (spec.category, spec.variant, spec.scale.to_bits(), spec.material);
        Ok(match self.built.entry(key) {
            Entry::Occupied(e) => e.into_mut(),
            Entry::Vacant(v) => v.insert(Asset::build_spec(spec)?),
        })
    }
}

/// The category of an object, or the error naming it.
pub(crate) fn category_of(o: &SceneObject) -> Result<Category, SceneError> {
    Category::from_name(&o.category).ok_or_else(|| SceneError::UnknownCategory {
        object: o.name.clone(),
        category: o.category.clone(),
    })
}

fn spec_of(o: &SceneObject) -> Result<AssetSpec, SceneError> {
    Ok(AssetSpec {
        category: category_of(o)?,
        variant: o.variant,
        scale: o.scale,
        material: o.material,
    })
}

impl SceneFile {
    /// Checks the whole scene; the first problem found is returned.
    ///
    /// ```
    /// use hearth_sim::scene::{SceneError, SceneFile, SceneObject};
    /// let mut s = SceneFile::empty("two tables");
    /// s.objects.push(SceneObject::new("a", "table", 0, [0.0, 0.0, 0.0]));
    /// s.objects.push(SceneObject::new("b", "table", 0, [0.5, 0.0, 0.0]));
    /// assert!(matches!(s.validate(), Err(SceneError::Overlap { .. })));
    /// ```
    pub fn validate(&self) -> Result<(), SceneError> {
        self.assets().map(|_| ())
    }

    /// Validates the scene and returns each object's asset, in object order.
    ///
    /// ```
    /// use hearth_sim::scene::{SceneFile, SceneObject};
    /// let mut s = SceneFile::empty("one mug");
    /// s.objects.push(SceneObject::new("m", "mug", 2, [0.0, 0.0, 0.0]));
    /// assert!(s.assets().unwrap()[0].mass > 0.1);
    /// ```
    pub fn assets(&self) -> Result<Vec<Asset>, SceneError> {
        self.check_numbers()?;
        self.check_building()?;
        unique("object", self.objects.iter().map(|o| o.name.as_str()))?;
        let mut cache = AssetCache::default();
        let mut assets = Vec::with_capacity(self.objects.len());
        for o in &self.objects {
            let spec = spec_of(o)?;
            let asset = cache.get(&spec).map_err(|reason| SceneError::Asset {
                object: o.name.clone(),
                reason: Box::new(reason),
            })?;
            check_joints(o, asset)?;
            assets.push(asset.clone());
        }
        self.check_supports()?;
        self.check_overlaps(&assets)?;
        Ok(assets)
    }

    fn check_numbers(&self) -> Result<(), SceneError> {
        let b = &self.building;
        for (kind, slabs) in [("floors", &b.floors), ("ceilings", &b.ceilings)] {
            for (i, s) in slabs.iter().enumerate() {
                finite(|| format!("building.{kind}[{i}] (`{}`)", s.name), &[s.z, s.thickness])?;
                finite(|| format!("building.{kind}[{i}].polygon"), s.polygon.as_flattened())?;
            }
        }
        for (i, w) in b.walls.iter().enumerate() {
            let n = || format!("building.walls[{i}] (`{}`)", w.name);
            finite(n, &[w.start[0], w.start[1], w.end[0], w.end[1], w.height, w.thickness])?;
            for (k, o) in w.openings.iter().enumerate() {
                finite(
                    || format!("building.walls[{i}].openings[{k}]"),
                    &[o.center, o.width, o.bottom, o.height],
                )?;
            }
        }
        for (i, r) in b.rooms.iter().enumerate() {
            finite(
                || format!("building.rooms[{i}].polygon (`{}`)", r.name),
                r.polygon.as_flattened(),
            )?;
        }
        for (i, o) in self.objects.iter().enumerate() {
            let n = || format!("objects[{i}] (`{}`)", o.name);
            finite(|| format!("{}.position", n()), &o.position)?;
            match o.orientation {
                super::Orientation::Yaw(y) => finite(|| format!("{}.orientation.yaw", n()), &[y])?,
                super::Orientation::QuatXyzw(q) => finite(|| format!("{}.orientation.quat_xyzw", n()), &q)?,
            }
            finite(|| format!("{}.scale", n()), &[o.scale])?;
            for (j, v) in &o.joints {
                finite(|| format!("{}.joints.{j}", n()), &[*v])?;
            }
            if let Some(bb) = &o.bbox {
                finite(|| format!("{}.bbox", n()), &[bb.min, bb.max].concat())?;
            }
        }
        for (i, l) in self.lights.iter().enumerate() {
            let n = || format!("lights[{i}] (`{}`)", l.name);
            finite(
                n,
                &[
                    l.position.as_slice(),
                    &l.color,
                    &[l.intensity],
                    l.direction.as_ref().map_or(&[], |d| d),
                ]
                .concat(),
            )?;
        }
        if let Some(r) = &self.robot {
            finite(
                || "robot".to_owned(),
                &[r.position[0], r.position[1], r.position[2], r.yaw],
            )?;
        }
        Ok(())
    }

    fn check_building(&self) -> Result<(), SceneError> {
        let b = &self.building;
        unique("wall", b.walls.iter().map(|w| w.name.as_str()))?;
        unique("room", b.rooms.iter().map(|r| r.name.as_str()))?;
        for (i, w) in b.walls.iter().enumerate() {
            let n = || format!("building.walls[{i}] (`{}`)", w.name);
            positive(|| format!("{}.length", n()), w.length())?;
            positive(|| format!("{}.height", n()), w.height)?;
            positive(|| format!("{}.thickness", n()), w.thickness)?;
            for (k, o) in w.openings.iter().enumerate() {
                let f = || format!("{}.openings[{k}]", n());
                positive(|| format!("{}.width", f()), o.width)?;
                positive(|| format!("{}.height", f()), o.height)?;
                if o.center - o.width / 2.0 < -1e-9 || o.center + o.width / 2.0 > w.length() + 1e-9 || o.bottom < 0.0 {
                    return Err(SceneError::invalid(f(), "the opening does not lie within the wall"));
                }
            }
        }
        for (i, r) in b.rooms.iter().enumerate() {
            if r.polygon.len() < 3 {
                return Err(SceneError::invalid(
                    format!("building.rooms[{i}] (`{}`)", r.name),
                    "a polygon needs 3 or more points",
                ));
            }
        }
        for (kind, slabs) in [("floors", &b.floors), ("ceilings", &b.ceilings)] {
            for (i, s) in slabs.iter().enumerate() {
                if s.polygon.len() < 3 {
                    return Err(SceneError::invalid(
                        format!("building.{kind}[{i}] (`{}`)", s.name),
                        "a polygon needs 3 or more points",
                    ));
                }
                positive(|| format!("building.{kind}[{i}].thickness"), s.thickness)?;
            }
        }
        Ok(())
    }

    fn check_supports(&self) -> Result<(), SceneError> {
        let names: HashSet<&str> = self.objects.iter().map(|o| o.name.as_str()).collect();
        for o in &self.objects {
            if let Some(s) = &o.on
                && (s == &o.name || !names.contains(s.as_str()))
            {
                return Err(SceneError::UnknownSupport {
                    object: o.name.clone(),
                    support: s.clone(),
                });
            }
        }
        Ok(())
    }

    fn check_overlaps(&self, assets: &[Asset]) -> Result<(), SceneError> {
        let prints: Vec<Option<Footprint>> = self
            .objects
            .iter()
            .zip(assets)
            .map(|(o, a)| match a.category.placement() {
                Placement::FloorCovering => None,
                _ => Some(Footprint::of_box(&o.pose(), &a.aabb_min, &a.aabb_max)),
            })
            .collect();
        let mut order: Vec<usize> = (0..prints.len()).filter(|&i| prints[i].is_some()).collect();
        order.sort_by(|&i, &j| {
            let (a, b) = (
                prints[i].map_or(0.0, |f| f.aabb().0[0]),
                prints[j].map_or(0.0, |f| f.aabb().0[0]),
            );
            a.total_cmp(&b)
        });
        // Sweep along x: only pairs whose x ranges meet are tested.
        for (k, &i) in order.iter().enumerate() {
            let Some(fi) = prints[i] else { continue };
            let reach = fi.aabb().1[0];
            for &j in &order[k + 1..] {
                let Some(fj) = prints[j] else { continue };
                if fj.aabb().0[0] > reach {
                    break;
                }
                let (a, b) = (&self.objects[i], &self.objects[j]);
                let resting = a.on.as_deref() == Some(b.name.as_str()) || b.on.as_deref() == Some(a.name.as_str());
                let in_wall = assets[i].category.placement() == Placement::InWall
                    && assets[j].category.placement() == Placement::InWall;
                if resting || in_wall {
                    continue;
                }
                let depth = fi.overlap(&fj);
                if depth > OVERLAP_TOLERANCE {
                    return Err(SceneError::Overlap {
                        a: a.name.clone(),
                        b: b.name.clone(),
                        depth,
                    });
                }
            }
        }
        for wall in &self.building.walls {
            for piece in wall.pieces() {
                let wp = Footprint::of_wall_piece(wall, piece);
                for (i, f) in prints.iter().enumerate() {
                    let Some(f) = f else { continue };
                    if assets[i].category.placement() == Placement::InWall {
                        continue;
                    }
                    let depth = f.overlap(&wp);
                    if depth > OVERLAP_TOLERANCE {
                        return Err(SceneError::WallOverlap {
                            object: self.objects[i].name.clone(),
                            wall: wall.name.clone(),
                            depth,
                        });
                    }
                }
            }
        }
        Ok(())
    }
}

fn check_joints(o: &SceneObject, asset: &Asset) -> Result<(), SceneError> {
    let model = &asset.model;
    for (name, &value) in &o.joints {
        let Some(k) = model.variable_names().iter().position(|n| n == name) else {
            return Err(SceneError::UnknownJoint {
                object: o.name.clone(),
                joint: name.clone(),
                known: if model.variable_names().is_empty() {
                    "none".to_owned()
                } else {
                    model.variable_names().join(", ")
                },
            });
        };
        let (lower, upper) = (model.lower()[k], model.upper()[k]);
        if value < lower - 1e-9 || value > upper + 1e-9 {
            return Err(SceneError::JointOutOfRange {
                object: o.name.clone(),
                joint: name.clone(),
                value,
                lower,
                upper,
            });
        }
    }
    Ok(())
}
