//! Finding mesh files: `package://` URIs, `file://` URIs and relative paths.

use std::path::{Path, PathBuf};

/// Environment variable with extra package roots (`:`-separated), searched first.
///
/// ```
/// use hearth_kinematics::{PACKAGE_PATH_ENV, PackageResolver};
/// let env_roots = std::env::var_os(PACKAGE_PATH_ENV).map_or(0, |v| std::env::split_paths(&v).count());
/// assert!(PackageResolver::new(vec![]).roots().len() >= env_roots.min(1));
/// assert_eq!(PACKAGE_PATH_ENV, "HEARTH_PACKAGE_PATH");
/// ```
pub const PACKAGE_PATH_ENV: &str = "HEARTH_PACKAGE_PATH";

/// Resolves the `filename` of a URDF `<mesh>`.
///
/// `package://NAME/REST` is looked up, in order, under every root of [`PACKAGE_PATH_ENV`],
/// `ROS_PACKAGE_PATH` and any roots added by the caller (as `ROOT/NAME/REST`, or `ROOT/REST`
/// when the root itself is named `NAME`), then under the URDF's own folder and each of its
/// parents (the same two forms), as PyBullet does — so URDFs that write `package://meshes/x.stl`
/// next to a `meshes/` folder load as they are. `file://` URIs and absolute paths are used as
/// given; relative paths are taken against the URDF's folder.
///
/// ```
/// use hearth_kinematics::PackageResolver;
/// let dir = std::env::temp_dir().join("hearth_doc_resolver/my_robot/meshes");
/// std::fs::create_dir_all(&dir).unwrap();
/// std::fs::write(dir.join("base.stl"), b"solid x\nendsolid x\n").unwrap();
/// let urdf_dir = dir.parent().unwrap().join("urdf");
/// let r = PackageResolver::new(vec![]);
/// let found = r.resolve("package://my_robot/meshes/base.stl", Some(&urdf_dir)).unwrap();
/// assert!(found.ends_with("my_robot/meshes/base.stl"));
/// ```
#[derive(Clone, Debug, Default)]
pub struct PackageResolver {
    roots: Vec<PathBuf>,
}

impl PackageResolver {
    /// A resolver with these extra roots (searched after the environment variables).
    ///
    /// ```
    /// use hearth_kinematics::PackageResolver;
    /// use std::path::PathBuf;
    /// let r = PackageResolver::new(vec![PathBuf::from("/opt/robots")]);
    /// assert_eq!(r.roots().last().unwrap(), &PathBuf::from("/opt/robots"));
    /// ```
    pub fn new(extra_roots: Vec<PathBuf>) -> Self {
        let mut roots = Vec::new();
        for var in [PACKAGE_PATH_ENV, "ROS_PACKAGE_PATH"] {
            if let Some(v) = std::env::var_os(var) {
                roots.extend(std::env::split_paths(&v).filter(|p| !p.as_os_str().is_empty()));
            }
        }
        roots.extend(extra_roots);
        Self { roots }
    }

    /// The roots searched for `package://` URIs (not counting the URDF's folders).
    ///
    /// ```
    /// use hearth_kinematics::PackageResolver;
    /// use std::path::PathBuf;
    /// let extra = vec![PathBuf::from("/a"), PathBuf::from("/b")];
    /// let r = PackageResolver::new(extra.clone());
    /// assert!(r.roots().ends_with(&extra));
    /// ```
    pub fn roots(&self) -> &[PathBuf] {
        &self.roots
    }

    /// Candidate paths for `uri`, in search order.
    ///
    /// ```
    /// use hearth_kinematics::PackageResolver;
    /// use std::path::{Path, PathBuf};
    /// let r = PackageResolver::default();
    /// let c = r.candidates("package://bot/meshes/a.stl", Some(Path::new("/ws/bot/urdf")));
    /// assert_eq!(c[0], PathBuf::from("/ws/bot/urdf/bot/meshes/a.stl"));
    /// assert!(c.contains(&PathBuf::from("/ws/bot/meshes/a.stl"))); // the folder named `bot`
    /// assert_eq!(r.candidates("meshes/a.stl", Some(Path::new("/ws"))), [PathBuf::from("/ws/meshes/a.stl")]);
    /// ```
    pub fn candidates(&self, uri: &str, urdf_dir: Option<&Path>) -> Vec<PathBuf> {
        if let Some(rest) = uri.strip_prefix("package://") {
            let (package, sub) = rest.split_once('/').unwrap_or((rest, ""));
            let mut out = Vec::new();
            let dirs = self
                .roots
                .iter()
                .map(PathBuf::as_path)
                .chain(urdf_dir.into_iter().flat_map(Path::ancestors));
            for dir in dirs {
                out.push(dir.join(package).join(sub));
                if dir.file_name().is_some_and(|n| n == package) {
                    out.push(dir.join(sub));
                }
            }
            out.dedup();
            out
        } else if let Some(path) = uri.strip_prefix("file://") {
            vec![PathBuf::from(path)]
        } else {
            let p = Path::new(uri);
            if p.is_absolute() {
                vec![p.to_path_buf()]
            } else {
                vec![urdf_dir.unwrap_or(Path::new(".")).join(p)]
            }
        }
    }

    /// The first candidate that is a file, or the list of candidates tried.
    ///
    /// ```
    /// use hearth_kinematics::PackageResolver;
    /// let dir = std::env::temp_dir().join("hearth_doc_resolve_fn");
    /// std::fs::create_dir_all(&dir).unwrap();
    /// std::fs::write(dir.join("part.stl"), b"solid x\nendsolid x\n").unwrap();
    /// let r = PackageResolver::default();
    /// assert_eq!(r.resolve("part.stl", Some(&dir)).unwrap(), dir.join("part.stl"));
    /// let tried = r.resolve("missing.stl", Some(&dir)).unwrap_err();
    /// assert_eq!(tried, [dir.join("missing.stl")]);
    /// ```
    pub fn resolve(&self, uri: &str, urdf_dir: Option<&Path>) -> Result<PathBuf, Vec<PathBuf>> {
        let candidates = self.candidates(uri, urdf_dir);
        match candidates.iter().find(|p| p.is_file()) {
            Some(p) => Ok(p.clone()),
            None => Err(candidates),
        }
    }
}
