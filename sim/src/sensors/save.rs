//! Writing frames to disk: PNG images (RGB; depth as 16-bit millimetres; segmentation colour
//! coded; normals; flows visualised) and raw `.npy` arrays (NumPy format 1.0) for everything
//! but RGB.

use std::io::Write;
use std::path::{Path, PathBuf};

use super::camera::{Frame, Modality};
use super::error::{SensorError, SensorResult};

fn io_error(path: &Path, e: impl std::fmt::Display) -> SensorError {
    SensorError::Io {
        path: path.display().to_string(),
        reason: e.to_string(),
    }
}

/// Element types `.npy` files are written with.
trait NpyElement: Copy {
    const DESCR: &'static str;
    fn write_le(self, out: &mut Vec<u8>);
}

impl NpyElement for f32 {
    const DESCR: &'static str = "<f4";
    fn write_le(self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
}

impl NpyElement for u32 {
    const DESCR: &'static str = "<u4";
    fn write_le(self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
}

/// Encodes `data` (row-major, `shape`) as a NumPy `.npy` file (format version 1.0).
fn npy_bytes<T: NpyElement>(data: &[T], shape: &[usize]) -> Vec<u8> {
    let dims: Vec<String> = shape.iter().map(ToString::to_string).collect();
    let shape_text = if dims.len() == 1 {
        format!("({},)", dims[0])
    } else {
        format!("({})", dims.join(", "))
    };
    let mut header = format!(
        "{{'descr': '{}', 'fortran_order': False, 'shape': {shape_text}, }}",
        T::DESCR
    );
    // Magic (6) + version (2) + header length (2) + header + '\n' is a multiple of 64.
    let unpadded = 10 + header.len() + 1;
    header.push_str(&" ".repeat((64 - unpadded % 64) % 64));
    header.push('\n');
    let mut out = Vec::with_capacity(10 + header.len() + data.len() * 4);
    out.extend_from_slice(b"\x93NUMPY\x01\x00");
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    for &x in data {
        x.write_le(&mut out);
    }
    out
}

fn write_file(path: &Path, bytes: &[u8]) -> SensorResult<()> {
    std::fs::File::create(path)
        .and_then(|mut f| f.write_all(bytes))
        .map_err(|e| io_error(path, e))
}

fn write_png(
    path: &Path,
    w: u32,
    h: u32,
    color: png::ColorType,
    depth: png::BitDepth,
    data: &[u8],
) -> SensorResult<()> {
    let file = std::fs::File::create(path).map_err(|e| io_error(path, e))?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), w, h);
    encoder.set_color(color);
    encoder.set_depth(depth);
    let mut writer = encoder.write_header().map_err(|e| io_error(path, e))?;
    writer.write_image_data(data).map_err(|e| io_error(path, e))?;
    writer.finish().map_err(|e| io_error(path, e))
}

/// A stable, well-spread colour for an id (0 is black).
///
/// ```
/// use hearth_sim::sensors::save::id_color;
/// assert_eq!(id_color(0), [0, 0, 0]);
/// assert_ne!(id_color(1), id_color(2));
/// ```
pub fn id_color(id: u32) -> [u8; 3] {
    if id == 0 {
        return [0, 0, 0];
    }
    // Golden-ratio hue steps, fixed saturation and value.
    let hue = (id as f32 * 0.618_034).fract();
    hsv_to_rgb(hue, 0.65, 0.95)
}

fn hsv_to_rgb(h: f32, s: f32, v: f32) -> [u8; 3] {
    let h6 = h.rem_euclid(1.0) * 6.0;
    let c = v * s;
    let x = c * (1.0 - ((h6 % 2.0) - 1.0).abs());
    let (r, g, b) = match h6 as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = v - c;
    [r + m, g + m, b + m].map(|t| (t.clamp(0.0, 1.0) * 255.0 + 0.5) as u8)
}

impl Frame {
    /// Writes every modality of the frame into `dir` (created if missing) as `PREFIX<name>.png`
    /// and, for all but RGB, `PREFIX<name>.npy`; returns the paths written.
    ///
    /// - `rgb.png`: RGB8.
    /// - `depth.png`: 16-bit grey, millimetres (saturating at 65.535 m); `depth.npy`: f32 m.
    /// - `normal.png`: (n + 1) / 2 as RGB8; `normal.npy`: (H, W, 3) f32.
    /// - `seg.png`, `ins_seg.png`: ids colour coded ([`id_color`]); `.npy`: u32 ids.
    /// - `optical_flow.png`: direction as hue, magnitude as brightness; `.npy`: (H, W, 2) f32.
    /// - `scene_flow.png`: |Δ| per axis scaled to the frame's largest; `.npy`: (H, W, 3) f32.
    /// - `pc.png`: not written; `pc.npy`: (H, W, 3) f32.
    ///
    /// # Errors
    /// [`SensorError::Io`] when a file cannot be written.
    ///
    /// ```
    /// use hearth_sim::sensors::{Frame, Modality, ModalitySet};
    /// let mut f = Frame::default();
    /// f.prepare(2, 2, ModalitySet::EMPTY.with(Modality::Depth));
    /// let dir = std::env::temp_dir().join(format!("hearth-save-doc-{}", std::process::id()));
    /// let written = f.save(&dir, "").unwrap();
    /// assert_eq!(written.len(), 2);
    /// std::fs::remove_dir_all(&dir).unwrap();
    /// ```
    pub fn save(&self, dir: &Path, prefix: &str) -> SensorResult<Vec<PathBuf>> {
        std::fs::create_dir_all(dir).map_err(|e| io_error(dir, e))?;
        let (w, h) = (self.width, self.height);
        let (wu, hu) = (w as usize, h as usize);
        let mut written = Vec::new();
        let path = |name: &str, ext: &str| dir.join(format!("{prefix}{name}.{ext}"));
        let rgb8 = png::ColorType::Rgb;
        let eight = png::BitDepth::Eight;
        for m in self.modalities.iter() {
            let name = m.name();
            match m {
                Modality::Rgb => {
                    let p = path(name, "png");
                    write_png(&p, w, h, rgb8, eight, &self.rgb)?;
                    written.push(p);
                }
                Modality::Depth => {
                    let mm: Vec<u8> = self
                        .depth
                        .iter()
                        .flat_map(|&d| ((d * 1000.0).round().clamp(0.0, 65535.0) as u16).to_be_bytes())
                        .collect();
                    let p = path(name, "png");
                    write_png(&p, w, h, png::ColorType::Grayscale, png::BitDepth::Sixteen, &mm)?;
                    written.push(p);
                    let p = path(name, "npy");
                    write_file(&p, &npy_bytes(&self.depth, &[hu, wu]))?;
                    written.push(p);
                }
                Modality::Normal => {
                    let img: Vec<u8> = self
                        .normal
                        .iter()
                        .flat_map(|n| n.map(|c| ((c + 1.0) * 0.5 * 255.0).round().clamp(0.0, 255.0) as u8))
                        .collect();
                    let p = path(name, "png");
                    write_png(&p, w, h, rgb8, eight, &img)?;
                    written.push(p);
                    let flat: Vec<f32> = self.normal.iter().flatten().copied().collect();
                    let p = path(name, "npy");
                    write_file(&p, &npy_bytes(&flat, &[hu, wu, 3]))?;
                    written.push(p);
                }
                Modality::Seg | Modality::InsSeg => {
                    let ids = if m == Modality::Seg { &self.seg } else { &self.ins_seg };
                    let img: Vec<u8> = ids.iter().flat_map(|&id| id_color(id)).collect();
                    let p = path(name, "png");
                    write_png(&p, w, h, rgb8, eight, &img)?;
                    written.push(p);
                    let p = path(name, "npy");
                    write_file(&p, &npy_bytes(ids, &[hu, wu]))?;
                    written.push(p);
                }
                Modality::OpticalFlow => {
                    let max = self
                        .optical_flow
                        .iter()
                        .map(|f| f[0].hypot(f[1]))
                        .fold(1e-6f32, f32::max);
                    let img: Vec<u8> = self
                        .optical_flow
                        .iter()
                        .flat_map(|f| {
                            let hue = f[1].atan2(f[0]) / std::f32::consts::TAU + 0.5;
                            hsv_to_rgb(hue, 1.0, f[0].hypot(f[1]) / max)
                        })
                        .collect();
                    let p = path(name, "png");
                    write_png(&p, w, h, rgb8, eight, &img)?;
                    written.push(p);
                    let flat: Vec<f32> = self.optical_flow.iter().flatten().copied().collect();
                    let p = path(name, "npy");
                    write_file(&p, &npy_bytes(&flat, &[hu, wu, 2]))?;
                    written.push(p);
                }
                Modality::SceneFlow | Modality::Pc => {
                    let data = if m == Modality::Pc { &self.pc } else { &self.scene_flow };
                    if m == Modality::SceneFlow {
                        let max = data.iter().flatten().fold(1e-6f32, |a, &b| a.max(b.abs()));
                        let img: Vec<u8> = data
                            .iter()
                            .flat_map(|v| v.map(|c| (c.abs() / max * 255.0).round() as u8))
                            .collect();
                        let p = path(name, "png");
                        write_png(&p, w, h, rgb8, eight, &img)?;
                        written.push(p);
                    }
                    let flat: Vec<f32> = data.iter().flatten().copied().collect();
                    let p = path(name, "npy");
                    write_file(&p, &npy_bytes(&flat, &[hu, wu, 3]))?;
                    written.push(p);
                }
            }
        }
        Ok(written)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn npy_header_is_aligned_and_describes_the_array() {
        let bytes = npy_bytes(&[1.0f32, 2.0, 3.0, 4.0, 5.0, 6.0], &[2, 3]);
        assert_eq!(&bytes[..8], b"\x93NUMPY\x01\x00");
        let len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
        assert_eq!((10 + len) % 64, 0);
        let header = std::str::from_utf8(&bytes[10..10 + len]).unwrap();
        assert!(
            header.contains("'descr': '<f4'") && header.contains("'shape': (2, 3)"),
            "{header}"
        );
        assert!(header.ends_with('\n'));
        assert_eq!(bytes.len(), 10 + len + 24);
        assert_eq!(f32::from_le_bytes(bytes[10 + len..14 + len].try_into().unwrap()), 1.0);
        let one = npy_bytes(&[7u32], &[1]);
        assert!(std::str::from_utf8(&one[10..]).unwrap().contains("'shape': (1,)"));
    }
}
