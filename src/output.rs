//! Writing outputs: every file the command line writes goes through [`AtomicFile`] (a
//! temporary file in the destination's folder, flushed, synced and renamed over the
//! destination, so a reader or a killed process never sees a half-written file), and the
//! PNG writers of DAC codes, raw taps and difference maps use it.

use crate::error::{Error, Result};
use image::{ImageBuffer, ImageFormat, Luma, Rgb};
use std::fs::{File, OpenOptions};
use std::io::{self, BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Why `dest` cannot be an output file (a phrase after the path: `is a folder; ...`), found
/// without writing anything: it names no file
/// (empty, `.`, `..`, or ending in `/`), it is a folder, or it is a read-only file.
/// [`AtomicFile::create`] refuses these; the command line checks every output with it
/// before any work, so a bad path is refused before the first file is written.
pub fn unwritable(dest: &Path) -> Option<&'static str> {
    if dest.file_name().is_none() || dest.as_os_str().to_string_lossy().ends_with('/') {
        return Some("is not a file name; name a file");
    }
    let m = std::fs::metadata(dest).ok()?;
    if m.is_dir() {
        Some("is a folder; name a file in it")
    } else if m.permissions().readonly() {
        Some("is read-only; make it writable or choose another path")
    } else {
        None
    }
}

/// Why `dir` cannot be an output folder (a phrase after the path; created with its missing parents when written),
/// found without writing anything: it is empty (`.` names the current folder), or it or
/// one of its parents is a file.
pub fn unwritable_folder(dir: &Path) -> Option<String> {
    if dir.as_os_str().is_empty() {
        return Some("is not a file name; name a folder (`.` is the current one)".into());
    }
    let existing = dir
        .ancestors()
        .find(|a| !a.as_os_str().is_empty() && std::fs::symlink_metadata(a).is_ok())?;
    if existing.is_dir() {
        None
    } else if existing == dir {
        Some("is a file, not a folder; name a folder (it is created if missing)".into())
    } else {
        Some(format!(
            "is inside {}, which is a file, not a folder; name a folder (it is created if missing)",
            existing.display()
        ))
    }
}

/// An output file being written: the bytes go to a temporary file `.<name>.<pid>.<n>.tmp`
/// in the destination's folder; [`AtomicFile::commit`] flushes and syncs it and renames it
/// over the destination. Dropped without a commit (an error, a panic), the temporary is
/// removed and the destination is untouched. A process killed while writing leaves the
/// destination as it was (and the hidden temporary behind). A destination that is a special
/// file (a device such as `/dev/null`, a FIFO, a socket) is written in place instead: it
/// cannot be replaced by a rename, and is not a file a reader could see half-written.
pub struct AtomicFile {
    dest: PathBuf,
    tmp: PathBuf,
    file: Option<BufWriter<File>>,
}

/// The error of an output: names the destination, says what failed and what to do.
fn out_error(dest: &Path, what: String, e: &io::Error) -> Error {
    Error::Io {
        path: dest.display().to_string(),
        source: io::Error::new(e.kind(), format!("{what}: {e}")),
    }
}

impl AtomicFile {
    /// Opens a temporary file next to `dest`. Refuses a destination that is a folder or a
    /// read-only file; the destination's permissions carry over to the new file.
    pub fn create(dest: impl AsRef<Path>) -> Result<AtomicFile> {
        static SERIAL: AtomicU64 = AtomicU64::new(0);
        let dest = dest.as_ref();
        if let Some(why) = unwritable(dest) {
            return Err(out_error(
                dest,
                "cannot write".into(),
                &io::Error::other(why),
            ));
        }
        let name = dest.file_name().expect("checked by unwritable");
        let existing = std::fs::metadata(dest).ok();
        if existing.as_ref().is_some_and(is_special) {
            // A device, pipe or socket (`/dev/null`, a FIFO): written in place, since a
            // rename would replace the special file itself.
            let file = OpenOptions::new()
                .write(true)
                .open(dest)
                .map_err(|e| out_error(dest, "cannot open".into(), &e))?;
            return Ok(AtomicFile {
                dest: dest.to_path_buf(),
                tmp: PathBuf::new(),
                file: Some(BufWriter::new(file)),
            });
        }
        let dir = match dest.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let pid = std::process::id();
        let mut attempt = 0;
        let (tmp, file) = loop {
            let n = SERIAL.fetch_add(1, Ordering::Relaxed);
            let tmp = dir.join(format!(".{}.{pid}.{n}.tmp", name.to_string_lossy()));
            match OpenOptions::new().write(true).create_new(true).open(&tmp) {
                Ok(f) => break (tmp, f),
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists && attempt < 100 => {
                    attempt += 1;
                }
                Err(e) => {
                    return Err(out_error(
                        dest,
                        format!(
                            "cannot create a temporary file in {}; check that the folder exists and is writable",
                            dir.display()
                        ),
                        &e,
                    ));
                }
            }
        };
        if let Some(m) = existing
            && let Err(e) = file.set_permissions(m.permissions())
        {
            let _ = std::fs::remove_file(&tmp);
            return Err(out_error(dest, "cannot copy its permissions".into(), &e));
        }
        Ok(AtomicFile {
            dest: dest.to_path_buf(),
            tmp,
            file: Some(BufWriter::new(file)),
        })
    }

    /// The destination.
    pub fn path(&self) -> &Path {
        &self.dest
    }

    /// Flushes and syncs the temporary and renames it over the destination (on failure the
    /// temporary is removed and the destination untouched).
    pub fn commit(mut self) -> Result<()> {
        let w = self.file.take().expect("open until commit");
        let file = match w.into_inner() {
            Ok(f) => f,
            Err(e) => return Err(self.fail("cannot write", e.error())),
        };
        if self.tmp.as_os_str().is_empty() {
            // A special file, written in place: nothing to sync or rename.
            return Ok(());
        }
        if let Err(e) = file.sync_all() {
            return Err(self.fail("cannot write", &e));
        }
        drop(file);
        if let Err(e) = std::fs::rename(&self.tmp, &self.dest) {
            return Err(self.fail("cannot rename the temporary file over it", &e));
        }
        // The rename is durable once the folder is synced (best effort: not every file
        // system can sync a folder).
        if let Some(dir) = self.tmp.parent()
            && let Ok(d) = File::open(if dir.as_os_str().is_empty() {
                Path::new(".")
            } else {
                dir
            })
        {
            let _ = d.sync_all();
        }
        self.tmp = PathBuf::new();
        Ok(())
    }

    fn fail(&mut self, what: &str, e: &io::Error) -> Error {
        let err = out_error(
            &self.dest,
            format!("{what} (temporary {})", self.tmp.display()),
            e,
        );
        self.discard();
        err
    }

    fn discard(&mut self) {
        drop(self.file.take());
        if !self.tmp.as_os_str().is_empty() {
            let _ = std::fs::remove_file(&self.tmp);
            self.tmp = PathBuf::new();
        }
    }

    fn writer(&mut self) -> &mut BufWriter<File> {
        self.file.as_mut().expect("open until commit")
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.writer().write(buf)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.writer().flush()
    }
}

impl Seek for AtomicFile {
    fn seek(&mut self, pos: SeekFrom) -> io::Result<u64> {
        self.writer().seek(pos)
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        self.discard();
    }
}

/// Writes `dest` atomically with `f` (see [`AtomicFile`]); an error of `f` leaves the
/// destination untouched and no temporary behind.
pub fn write_with(
    dest: impl AsRef<Path>,
    f: impl FnOnce(&mut AtomicFile) -> io::Result<()>,
) -> Result<()> {
    let mut out = AtomicFile::create(dest)?;
    if let Err(e) = f(&mut out) {
        let dest = out.dest.clone();
        drop(out);
        return Err(out_error(&dest, "cannot write".into(), &e));
    }
    out.commit()
}

/// Writes `bytes` to `dest` atomically.
pub fn write_file(dest: impl AsRef<Path>, bytes: impl AsRef<[u8]>) -> Result<()> {
    write_with(dest, |w| w.write_all(bytes.as_ref()))
}

/// Whether file metadata is of a special file (neither a regular file nor a folder).
fn is_special(m: &std::fs::Metadata) -> bool {
    !m.is_file() && !m.is_dir()
}

/// The image format of an output path: from its extension (`.png`; the PNG encoder is the
/// one built in, so another extension is refused by the encoder with its name), and PNG
/// for a path without an extension that is a special file (`-o /dev/null`, a FIFO).
fn image_format(path: &str) -> image::ImageResult<ImageFormat> {
    let p = Path::new(path);
    match ImageFormat::from_path(p) {
        Err(_) if p.extension().is_none() && std::fs::metadata(p).is_ok_and(|m| is_special(&m)) => {
            Ok(ImageFormat::Png)
        }
        r => r,
    }
}

fn save<P: image::Pixel<Subpixel = S> + image::PixelWithColorType, S: image::Primitive>(
    img: ImageBuffer<P, Vec<S>>,
    path: &str,
) -> Result<()>
where
    [S]: image::EncodableLayout,
{
    let image_error = |e: image::ImageError| Error::Image {
        path: path.into(),
        msg: e.to_string(),
    };
    let format = image_format(path).map_err(|e| Error::Image {
        path: path.into(),
        msg: format!(
            "{e}: images are written as PNG; name the file .png (a special file such as /dev/null needs no extension)"
        ),
    })?;
    let mut out = AtomicFile::create(path)?;
    img.write_to(&mut out, format).map_err(image_error)?;
    out.commit()
}

/// Writes DAC codes of `bits` width: 8-bit PNG for `bits <= 8`, else 16-bit, each code
/// scaled to the PNG's full range by `round(code * (2^png - 1) / (2^bits - 1))`
/// (exact identity for 8 and 16 bits).
pub fn write_dac(path: &str, codes: &[u16], width: u32, height: u32, bits: u32) -> Result<()> {
    let max = ((1u32 << bits) - 1) as f64;
    if bits <= 8 {
        let data = dac_to_u8(codes, bits);
        save(
            ImageBuffer::<Luma<u8>, _>::from_raw(width, height, data).expect("size matches"),
            path,
        )
    } else {
        let data: Vec<u16> = codes
            .iter()
            .map(|&c| (c as f64 * 65535.0 / max).round() as u16)
            .collect();
        save(
            ImageBuffer::<Luma<u16>, _>::from_raw(width, height, data).expect("size matches"),
            path,
        )
    }
}

/// Writes an RGB image of DAC codes, one plane per channel (R, G, B) of its own width
/// (`bits`, e.g. 5-6-5): an 8-bit RGB PNG when every channel has at most 8 bits, else 16-bit,
/// each channel scaled to the PNG's full range as in [`write_dac`].
pub fn write_rgb(
    path: &str,
    planes: [&[u16]; 3],
    bits: [u32; 3],
    width: u32,
    height: u32,
) -> Result<()> {
    let max = bits.map(|b| ((1u32 << b) - 1) as f64);
    let n = planes[0].len();
    // Interleaved R, G, B, each channel scaled to `top`.
    let scaled = |top: f64| (0..3 * n).map(move |k| planes[k % 3][k / 3] as f64 * top / max[k % 3]);
    if bits.iter().all(|&b| b <= 8) {
        let data: Vec<u8> = scaled(255.0).map(|v| v.round() as u8).collect();
        save(
            ImageBuffer::<Rgb<u8>, _>::from_raw(width, height, data).expect("size matches"),
            path,
        )
    } else {
        let data: Vec<u16> = scaled(65535.0).map(|v| v.round() as u16).collect();
        save(
            ImageBuffer::<Rgb<u16>, _>::from_raw(width, height, data).expect("size matches"),
            path,
        )
    }
}

/// Three planes of one 8-bit value per pixel interleaved as R, G, B (for [`write_rgb8`]).
pub fn interleave(planes: &[Vec<u8>]) -> Vec<u8> {
    (0..planes[0].len())
        .flat_map(|p| planes.iter().map(move |m| m[p]))
        .collect()
}

/// Writes 8-bit RGB values as they are (`data` interleaved R, G, B per pixel).
pub fn write_rgb8(path: &str, data: &[u8], width: u32, height: u32) -> Result<()> {
    save(
        ImageBuffer::<Rgb<u8>, _>::from_raw(width, height, data.to_vec()).expect("size matches"),
        path,
    )
}

/// Writes raw codes (unscaled) as a 16-bit grey PNG; codes above 65535 are an error.
pub fn write_raw16(path: &str, codes: &[u32], width: u32, height: u32) -> Result<()> {
    if let Some(&c) = codes.iter().find(|&&c| c > u16::MAX as u32) {
        return Err(Error::Image {
            path: path.into(),
            msg: format!("code {c} does not fit a 16-bit PNG"),
        });
    }
    let data: Vec<u16> = codes.iter().map(|&c| c as u16).collect();
    save(
        ImageBuffer::<Luma<u16>, _>::from_raw(width, height, data).expect("size matches"),
        path,
    )
}

/// Writes a signed difference map: 128 = identical, each code of difference is 32 grey
/// levels (fixed above the reference is brighter), clamped.
pub fn write_diff(
    path: &str,
    fixed: &[u16],
    reference: &[u16],
    width: u32,
    height: u32,
) -> Result<()> {
    let data = diff_values(fixed, reference);
    save(
        ImageBuffer::<Luma<u8>, _>::from_raw(width, height, data).expect("size matches"),
        path,
    )
}

/// The difference map's values (see [`write_diff`]).
pub fn diff_values(fixed: &[u16], reference: &[u16]) -> Vec<u8> {
    fixed
        .iter()
        .zip(reference)
        .map(|(&a, &b)| (128 + 32 * (a as i32 - b as i32)).clamp(0, 255) as u8)
        .collect()
}

/// Writes 8-bit grey values as they are.
pub fn write_raw8(path: &str, data: &[u8], width: u32, height: u32) -> Result<()> {
    save(
        ImageBuffer::<Luma<u8>, _>::from_raw(width, height, data.to_vec()).expect("size matches"),
        path,
    )
}

/// A writer the PNG encoder owns that appends to a buffer the caller keeps.
#[derive(Clone, Default)]
struct Shared(std::sync::Arc<std::sync::Mutex<Vec<u8>>>);

impl Write for Shared {
    fn write(&mut self, b: &[u8]) -> io::Result<usize> {
        self.0
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .extend_from_slice(b);
        Ok(b.len())
    }
    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

/// An animated PNG (APNG) of 8-bit grey frames, encoded in memory frame by frame as they
/// come; [`Apng::finish_bytes`] gives the file, which the caller writes atomically
/// ([`write_file`]), so a run that stops early leaves no file. `path` names it in errors.
pub struct Apng {
    path: String,
    buf: Shared,
    writer: png::Writer<Shared>,
    size: usize,
}

impl Apng {
    /// An APNG of `frames` frames of `width x height` shown at `rate_hz`, looping: 8-bit
    /// grey, or 8-bit RGB when `rgb`.
    pub fn new(
        path: &str,
        width: u32,
        height: u32,
        frames: u32,
        rate_hz: f64,
        rgb: bool,
    ) -> Result<Apng> {
        let err = |e: png::EncodingError| Error::Image {
            path: path.into(),
            msg: e.to_string(),
        };
        let buf = Shared::default();
        let mut enc = png::Encoder::new(buf.clone(), width, height);
        enc.set_color(if rgb {
            png::ColorType::Rgb
        } else {
            png::ColorType::Grayscale
        });
        enc.set_depth(png::BitDepth::Eight);
        enc.set_animated(frames, 0).map_err(err)?;
        // The delay num / den s: exact for rates with two decimals up to 655 Hz.
        let (num, den) = if rate_hz * 100.0 <= u16::MAX as f64 {
            (100, (rate_hz * 100.0).round() as u16)
        } else {
            (1, rate_hz.round().min(u16::MAX as f64) as u16)
        };
        enc.set_frame_delay(num, den.max(1)).map_err(err)?;
        let writer = enc.write_header().map_err(err)?;
        Ok(Apng {
            path: path.into(),
            buf,
            writer,
            size: width as usize * height as usize * if rgb { 3 } else { 1 },
        })
    }

    /// Adds the next frame (`width x height` grey values, or R, G, B triples, row-major).
    pub fn frame(&mut self, data: &[u8]) -> Result<()> {
        assert_eq!(data.len(), self.size, "an APNG frame of the announced size");
        self.writer
            .write_image_data(data)
            .map_err(|e| Error::Image {
                path: self.path.clone(),
                msg: e.to_string(),
            })
    }

    /// Ends the stream and gives the file's bytes (every announced frame must have been
    /// added).
    pub fn finish_bytes(self) -> Result<Vec<u8>> {
        let path = self.path;
        self.writer.finish().map_err(|e| Error::Image {
            path,
            msg: e.to_string(),
        })?;
        Ok(std::mem::take(
            &mut *self.buf.0.lock().unwrap_or_else(|e| e.into_inner()),
        ))
    }
}

/// DAC codes of `bits` width as 8-bit grey values (as [`write_dac`] scales them).
pub fn dac_to_u8(codes: &[u16], bits: u32) -> Vec<u8> {
    let max = ((1u32 << bits) - 1) as f64;
    codes
        .iter()
        .map(|&c| (c as f64 * 255.0 / max).round() as u8)
        .collect()
}
