//! The asset library: every category and variant builds into a sane, loadable URDF.

use hearth_kinematics::{Geometry, JointKind, RobotModel};
use hearth_sim::assets::{Asset, AssetError, AssetSpec, Category, Material, Placement};
use nalgebra::{Point3, Vector3};

fn all_assets() -> Vec<Asset> {
    Category::ALL
        .iter()
        .flat_map(|&c| {
            (0..c.variants()).map(move |v| Asset::build(c, v, 1.0).unwrap_or_else(|e| panic!("{c} {v}: {e}")))
        })
        .collect()
}

#[test]
fn library_has_thirty_categories_with_three_variants() {
    assert!(Category::ALL.len() >= 30, "{} categories", Category::ALL.len());
    for &c in Category::ALL {
        assert!(c.variants() >= 3, "{c}");
        assert_eq!(Category::from_name(c.name()), Some(c));
    }
    let required = [
        "bottom_cabinet",
        "top_cabinet",
        "counter",
        "fridge",
        "stove",
        "dishwasher",
        "table",
        "chair",
        "sofa",
        "bed",
        "shelf",
        "bookcase",
        "nightstand",
        "dresser",
        "desk",
        "tv_stand",
        "tv",
        "toilet",
        "bathtub",
        "lamp",
        "plant",
        "rug",
        "door",
        "window",
        "bowl",
        "mug",
        "plate",
        "bottle",
        "book",
        "laptop",
    ];
    for name in required {
        assert!(Category::from_name(name).is_some(), "missing {name}");
    }
}

#[test]
fn every_link_has_mass_inertia_collision_and_material() {
    for a in all_assets() {
        let tag = format!("{} {}", a.category, a.variant);
        assert!(a.mass > 0.0, "{tag}");
        let mut sum = 0.0;
        for l in a.model.links() {
            assert!(!l.collisions.is_empty(), "{tag}: link {} has no collision", l.name);
            assert_eq!(l.visuals.len(), l.collisions.len(), "{tag}");
            for v in &l.visuals {
                let m = v.material.as_deref().unwrap_or("");
                assert!(m.parse::<Material>().is_ok(), "{tag}: material `{m}`");
            }
            let i = l
                .inertial
                .as_ref()
                .unwrap_or_else(|| panic!("{tag}: {} has no inertial", l.name));
            assert!(i.mass > 0.0, "{tag}");
            sum += i.mass;
            // A physical inertia tensor: positive definite, triangle inequality on the principal moments.
            let eig = i.inertia.symmetric_eigen().eigenvalues;
            assert!(eig.iter().all(|&e| e > 0.0), "{tag} {}: {eig:?}", l.name);
            let (a0, a1, a2) = (eig[0], eig[1], eig[2]);
            let tol = 1e-9 * (a0 + a1 + a2);
            assert!(
                a0 + a1 >= a2 - tol && a1 + a2 >= a0 - tol && a0 + a2 >= a1 - tol,
                "{tag} {}",
                l.name
            );
        }
        assert!(
            (sum - a.mass).abs() < 1e-3 * a.mass.max(1.0),
            "{tag}: {sum} vs {}",
            a.mass
        );
    }
}

#[test]
fn masses_are_those_of_real_objects() {
    let mass = |c, v| Asset::build(c, v, 1.0).unwrap().mass;
    let within = |c: Category, lo: f64, hi: f64| {
        for v in 0..c.variants() {
            let m = mass(c, v);
            assert!(m >= lo && m <= hi, "{c} {v}: {m:.2} kg not in [{lo}, {hi}]");
        }
    };
    within(Category::Mug, 0.1, 0.6);
    within(Category::Plate, 0.2, 1.2);
    within(Category::Book, 0.2, 2.0);
    within(Category::Laptop, 0.8, 3.5);
    within(Category::Bowl, 0.1, 1.0);
    within(Category::Chair, 2.0, 35.0);
    within(Category::Table, 10.0, 60.0);
    within(Category::Fridge, 30.0, 150.0);
    within(Category::Stove, 30.0, 120.0);
    within(Category::Dishwasher, 30.0, 90.0);
    within(Category::Microwave, 8.0, 25.0);
    within(Category::Door, 15.0, 50.0);
    within(Category::Window, 10.0, 70.0);
    within(Category::Sofa, 30.0, 120.0);
    within(Category::Bed, 40.0, 140.0);
    within(Category::Toilet, 20.0, 60.0);
    within(Category::Lamp, 0.5, 5.0);
}

#[test]
fn joints_have_sane_limits_damping_and_friction() {
    let mut articulated = 0;
    for a in all_assets() {
        let tag = format!("{} {}", a.category, a.variant);
        articulated += usize::from(a.articulated);
        assert_eq!(a.articulated, a.model.dof() > 0, "{tag}");
        for j in a.model.joints() {
            match j.kind {
                JointKind::Prismatic => {
                    assert!(
                        j.limits.lower == 0.0 && j.limits.upper > 0.1 && j.limits.upper < 0.7,
                        "{tag} {}",
                        j.name
                    );
                }
                JointKind::Revolute => {
                    assert!(
                        j.limits.lower == 0.0 && j.limits.upper > 1.0 && j.limits.upper <= 2.3,
                        "{tag} {}",
                        j.name
                    );
                }
                _ => continue,
            }
            let d = j
                .dynamics
                .unwrap_or_else(|| panic!("{tag}: {} has no dynamics", j.name));
            assert!(d.damping > 0.0 && d.friction > 0.0, "{tag} {}", j.name);
            assert!(j.limits.effort > 0.0 && j.limits.velocity > 0.0, "{tag} {}", j.name);
        }
    }
    assert!(articulated >= 40, "{articulated} articulated variants");
    for c in [
        Category::BottomCabinet,
        Category::Fridge,
        Category::Door,
        Category::Laptop,
        Category::Dresser,
    ] {
        for v in 0..c.variants() {
            assert!(Asset::build(c, v, 1.0).unwrap().articulated, "{c} {v}");
        }
    }
}

fn geometry_half(g: &Geometry) -> Vector3<f64> {
    match g {
        Geometry::Box { half_extents } => *half_extents,
        Geometry::Cylinder { radius, length } => Vector3::new(*radius, *radius, length / 2.0),
        Geometry::Sphere { radius } => Vector3::repeat(*radius),
        other => panic!("unexpected geometry {other:?}"),
    }
}

#[test]
fn bounding_boxes_contain_every_collision_shape() {
    for a in all_assets() {
        let tag = format!("{} {}", a.category, a.variant);
        let q = vec![0.0; a.model.dof()];
        let mut poses = a.model.pose_buffer();
        a.model.fk(&q, &mut poses).unwrap();
        let mut lo = Vector3::repeat(f64::INFINITY);
        let mut hi = Vector3::repeat(f64::NEG_INFINITY);
        for (l, pose) in a.model.links().iter().zip(&poses) {
            for c in &l.collisions {
                let p = pose * c.origin;
                let half = p.rotation.to_rotation_matrix().matrix().abs() * geometry_half(&c.geometry);
                let centre = p * Point3::origin();
                lo = lo.inf(&(centre.coords - half));
                hi = hi.sup(&(centre.coords + half));
            }
        }
        let eps = 1e-5;
        assert!(
            (lo - a.aabb_min).amax() < eps && (hi - a.aabb_max).amax() < eps,
            "{tag}: {lo:?} {hi:?} vs {:?} {:?}",
            a.aabb_min,
            a.aabb_max
        );
        // Floor-standing assets start at the floor.
        if a.category.placement() != Placement::InWall {
            assert!(a.aabb_min.z.abs() < 1e-6, "{tag}: bottom at {}", a.aabb_min.z);
        }
        for s in &a.surfaces {
            assert!(
                s.max[0] > s.min[0] && s.max[1] > s.min[1] && s.clearance > 0.05,
                "{tag}: {s:?}"
            );
            assert!(
                s.min[0] >= a.aabb_min.x && s.max[0] <= a.aabb_max.x && s.z <= a.aabb_max.z + 1e-6,
                "{tag}: {s:?}"
            );
        }
    }
}

#[test]
fn urdf_text_is_deterministic_and_reloads() {
    for a in all_assets() {
        let again = Asset::build(a.category, a.variant, 1.0).unwrap();
        assert_eq!(a.urdf, again.urdf);
        let m = RobotModel::from_urdf_str(&a.urdf, None).unwrap();
        assert_eq!(m.links().len(), a.model.links().len());
    }
}

#[test]
fn scale_and_material_change_mass_as_physics_says() {
    let base = Asset::build(Category::Table, 0, 1.0).unwrap();
    let double = Asset::build(Category::Table, 0, 2.0).unwrap();
    assert!((double.mass / base.mass - 8.0).abs() < 1e-6);
    assert!((double.aabb_max.z / base.aabb_max.z - 2.0).abs() < 1e-9);
    let drawer = Asset::build(Category::Dresser, 0, 1.5).unwrap();
    let j = drawer
        .model
        .joints()
        .iter()
        .find(|j| j.kind == JointKind::Prismatic)
        .unwrap();
    let j1 = Asset::build(Category::Dresser, 0, 1.0).unwrap();
    let j1 = j1
        .model
        .joints()
        .iter()
        .find(|j| j.kind == JointKind::Prismatic)
        .unwrap()
        .limits
        .upper;
    assert!((j.limits.upper / j1 - 1.5).abs() < 1e-6);
    let metal = Asset::build_spec(&AssetSpec {
        material: Some(Material::Metal),
        ..AssetSpec::new(Category::Book, 0)
    })
    .unwrap();
    let paper = Asset::build(Category::Book, 0, 1.0).unwrap();
    let ratio = Material::Metal.props().density / Material::Paper.props().density;
    assert!((metal.mass / paper.mass - ratio).abs() < 1e-6);
}

#[test]
fn bad_specs_are_typed_errors() {
    assert!(matches!(
        Asset::build(Category::Mug, 3, 1.0),
        Err(AssetError::VariantOutOfRange { count: 3, .. })
    ));
    for s in [0.0, -1.0, f64::NAN, f64::INFINITY, 100.0] {
        assert!(
            matches!(Asset::build(Category::Mug, 0, s), Err(AssetError::BadScale { .. })),
            "{s}"
        );
    }
}

#[test]
fn material_table_is_complete_and_physical() {
    for m in Material::ALL {
        let p = m.props();
        assert!(p.friction > 0.0 && p.friction <= 1.5, "{m}");
        assert!((0.0..=1.0).contains(&p.restitution), "{m}");
        assert!(p.density > 10.0 && p.density < 20_000.0, "{m}");
        assert!(p.rgba.iter().all(|c| (0.0..=1.0).contains(c)), "{m}");
        assert_eq!(m.name().parse::<Material>().unwrap(), m);
    }
    assert!(Material::Metal.props().density > Material::Wood.props().density);
}
