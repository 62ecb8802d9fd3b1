//! One moment of a mission as pixels: the animation's drawing
//! ([`figures::mission_html`](crate::figures::mission_html)) rasterised, for the
//! environments' `render_mode="rgb_array"`. The same geometry and colours, without the
//! text: robots as dots in their task's colour (grey: no task; a red cross: failed; a
//! black ring: waiting for the rest of its team), tasks as squares sized by the work
//! left (filled while open, an outline once done).

use afg_mission::{Frame, Mission};

use crate::EvalError;
use crate::figures::mission_bounds;

/// The animation's canvas side, in its own pixels; a drawing of `size` scales it.
const CANVAS: f64 = 720.0;

/// `frame` of `mission` drawn on a `size` × `size` image, row-major RGB bytes
/// (`size · size · 3`), the first row at the top.
///
/// # Errors
/// [`EvalError::Figure`] for a size below 64 or above 4096, or a frame of another
/// mission (other numbers of robots or tasks).
///
/// # Examples
/// ```
/// use afg_mission::{MissionConfig, MissionEnv, Perception, Preset};
/// let mission = MissionConfig::new(Preset::Static, 10, 3, 1).generate()?;
/// let env = MissionEnv::new(mission.clone(), Perception::default())?;
/// let image = afg_eval::frame_image::frame_rgb(&mission, &env.frame(), 200)?;
/// assert_eq!(image.len(), 200 * 200 * 3);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn frame_rgb(mission: &Mission, frame: &Frame, size: usize) -> Result<Vec<u8>, EvalError> {
    if !(64..=4096).contains(&size) {
        return Err(EvalError::Figure(format!(
            "an image of {size} pixels: give 64 to 4096"
        )));
    }
    if frame.positions.len() != mission.robots.len() || frame.left.len() != mission.tasks.len() {
        return Err(EvalError::Figure(
            "the frame is not one of this mission (other numbers of robots or tasks)".into(),
        ));
    }
    let (lo, hi) = mission_bounds(mission);
    let span = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-9);
    let scale = size as f64 / CANVAS;
    let at = |x: f64, y: f64| {
        (
            scale * (20.0 + 680.0 * (x - lo[0]) / span),
            scale * (700.0 - 680.0 * (y - lo[1]) / span),
        )
    };
    let mut image = Image::new(size);
    for (j, (task, &left)) in mission.tasks.iter().zip(&frame.left).enumerate() {
        if left < 0.0 {
            continue; // not yet appeared
        }
        let (x, y) = at(task.position.x, task.position.y);
        let half = scale * (4.0 + 14.0 * f64::from(left).sqrt());
        let colour = hue(j);
        if left > 0.0 {
            image.fill_square(x, y, half, colour, 0.35);
        }
        image.stroke_square(x, y, half, 2.0 * scale, colour);
    }
    let dot = (2.5 * scale).max(2.0);
    for (p, &task) in frame.positions.iter().zip(&frame.tasks) {
        let (x, y) = at(f64::from(p[0]), f64::from(p[1]));
        match task {
            -2 => image.cross(x, y, 3.0 * scale, 1.5 * scale, RED),
            -1 => image.disc(x, y, dot, GREY),
            j => image.disc(x, y, dot, hue(j as usize)),
        }
    }
    for &i in &frame.waiting {
        let p = frame.positions[i as usize];
        let (x, y) = at(f64::from(p[0]), f64::from(p[1]));
        image.ring(x, y, (5.0 * scale).max(4.0), scale.max(1.0), BLACK);
    }
    Ok(image.into_bytes())
}

/// RGB bytes of a `size` × `size` image ([`frame_rgb`]'s) as a PNG file.
///
/// # Panics
/// If `rgb` is not `size · size · 3` bytes.
///
/// # Examples
/// ```
/// let png = afg_eval::frame_image::png(&vec![255; 64 * 64 * 3], 64);
/// assert!(png.starts_with(b"\x89PNG\r\n\x1a\n"));
/// ```
pub fn png(rgb: &[u8], size: usize) -> Vec<u8> {
    use std::io::Write as _;
    assert_eq!(rgb.len(), size * size * 3, "size × size RGB bytes");
    let mut rows = Vec::with_capacity(rgb.len() + size);
    for row in rgb.chunks_exact(size * 3) {
        rows.push(0); // filter: none
        rows.extend_from_slice(row);
    }
    let mut zlib = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
    zlib.write_all(&rows).expect("writing to memory");
    let data = zlib.finish().expect("writing to memory");
    let side = u32::try_from(size).expect("at most 4096 pixels");
    let mut header = Vec::with_capacity(13);
    header.extend_from_slice(&side.to_be_bytes());
    header.extend_from_slice(&side.to_be_bytes());
    header.extend_from_slice(&[8, 2, 0, 0, 0]); // 8-bit RGB, no interlace
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    for (kind, body) in [
        (b"IHDR", header.as_slice()),
        (b"IDAT", &data),
        (b"IEND", &[]),
    ] {
        let length = u32::try_from(body.len()).expect("a chunk under 4 GiB");
        out.extend_from_slice(&length.to_be_bytes());
        let mut crc = crc32fast::Hasher::new();
        crc.update(kind);
        crc.update(body);
        out.extend_from_slice(kind);
        out.extend_from_slice(body);
        out.extend_from_slice(&crc.finalize().to_be_bytes());
    }
    out
}

type Rgb = [f64; 3];
const GREY: Rgb = [0.6, 0.6, 0.6];
const RED: Rgb = [1.0, 0.0, 0.0];
const BLACK: Rgb = [0.0, 0.0, 0.0];

/// Task j's colour: the animation's `hsl(137.508 j, 70 %, 45 %)`.
fn hue(j: usize) -> Rgb {
    let (h, s, l) = ((j as f64 * 137.508) % 360.0 / 60.0, 0.7, 0.45);
    let c = (1.0 - (2.0 * l - 1.0f64).abs()) * s;
    let x = c * (1.0 - (h % 2.0 - 1.0).abs());
    let (r, g, b) = match h as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = l - c / 2.0;
    [r + m, g + m, b + m]
}

/// A white square canvas of colours in [0, 1], drawn on pixel by pixel (a pixel's
/// centre decides whether a shape covers it).
struct Image {
    size: usize,
    pixels: Vec<Rgb>,
}

impl Image {
    fn new(size: usize) -> Self {
        Image {
            size,
            pixels: vec![[1.0; 3]; size * size],
        }
    }

    /// Blends `colour` at opacity `alpha` into every pixel whose centre `inside`
    /// accepts, within the box around (x, y) of half-side `reach`.
    fn paint(
        &mut self,
        (x, y): (f64, f64),
        reach: f64,
        colour: Rgb,
        alpha: f64,
        inside: impl Fn(f64, f64) -> bool,
    ) {
        let last = self.size as f64 - 1.0;
        let range = |c: f64| {
            (
                (c - reach).floor().clamp(0.0, last) as usize,
                (c + reach).ceil().clamp(0.0, last) as usize,
            )
        };
        let ((x0, x1), (y0, y1)) = (range(x), range(y));
        for py in y0..=y1 {
            for px in x0..=x1 {
                let (dx, dy) = (px as f64 + 0.5 - x, py as f64 + 0.5 - y);
                if inside(dx, dy) {
                    let pixel = &mut self.pixels[py * self.size + px];
                    for (p, c) in pixel.iter_mut().zip(colour) {
                        *p = (1.0 - alpha) * *p + alpha * c;
                    }
                }
            }
        }
    }

    fn fill_square(&mut self, x: f64, y: f64, half: f64, colour: Rgb, alpha: f64) {
        self.paint((x, y), half, colour, alpha, |dx, dy| {
            dx.abs() <= half && dy.abs() <= half
        });
    }

    fn stroke_square(&mut self, x: f64, y: f64, half: f64, width: f64, colour: Rgb) {
        let w = width / 2.0;
        self.paint((x, y), half + w, colour, 1.0, |dx, dy| {
            let d = dx.abs().max(dy.abs());
            (d - half).abs() <= w
        });
    }

    fn disc(&mut self, x: f64, y: f64, radius: f64, colour: Rgb) {
        self.paint((x, y), radius, colour, 1.0, |dx, dy| dx.hypot(dy) <= radius);
    }

    fn ring(&mut self, x: f64, y: f64, radius: f64, width: f64, colour: Rgb) {
        let w = width / 2.0;
        self.paint((x, y), radius + w, colour, 1.0, |dx, dy| {
            (dx.hypot(dy) - radius).abs() <= w
        });
    }

    fn cross(&mut self, x: f64, y: f64, half: f64, width: f64, colour: Rgb) {
        let w = width / 2.0;
        self.paint((x, y), half, colour, 1.0, |dx, dy| {
            (dx - dy).abs() / 2f64.sqrt() <= w || (dx + dy).abs() / 2f64.sqrt() <= w
        });
    }

    fn into_bytes(self) -> Vec<u8> {
        self.pixels
            .iter()
            .flat_map(|p| p.map(|c| (c * 255.0).round().clamp(0.0, 255.0) as u8))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use afg_mission::{MissionConfig, Preset};

    /// Pixels by hand: one task in the middle of the box, half its work left; a robot
    /// on it waiting for its team, another with no task, one failed.
    #[test]
    fn a_frame_is_drawn_where_the_animation_draws_it() {
        let mut mission = MissionConfig::new(Preset::Static, 3, 1, 1)
            .generate()
            .unwrap();
        let (a, b) = (
            afg_game::Point::new(0.0, 0.0),
            afg_game::Point::new(1.0, 1.0),
        );
        mission.robots[0].position = a;
        mission.robots[1].position = b;
        mission.robots[2].position = b;
        mission.tasks[0].position = afg_game::Point::new(0.5, 0.5);
        let frame = Frame {
            time: 0.0,
            positions: vec![[0.5, 0.5], [0.0, 1.0], [1.0, 0.0]],
            tasks: vec![0, -1, -2],
            left: vec![0.25],
            waiting: vec![0],
        };
        let size = 720; // the animation's own pixels
        let image = frame_rgb(&mission, &frame, size).unwrap();
        let pixel = |x: usize, y: usize| &image[(y * size + x) * 3..][..3];
        // Box (0, 0)–(1, 1): x = 20 + 680 x, y = 700 − 680 y. The task at (360, 360),
        // half-side 4 + 14 · 0.5 = 11: the robot's dot (radius 2.5) in the task's
        // colour at the centre, its waiting ring (radius 5) black, the square's
        // translucent fill at 8 pixels from the centre, its outline at 11.
        let colour = hue(0).map(|c| (c * 255.0).round() as u8);
        assert_eq!(pixel(360, 360), colour);
        assert_eq!(pixel(364, 360), [0, 0, 0]);
        let fill = hue(0).map(|c| ((0.65 + 0.35 * c) * 255.0).round() as u8);
        assert_eq!(pixel(360 + 8, 360), fill);
        assert_eq!(pixel(360 + 11, 360 + 3), colour);
        // The idle robot at (20, 20) grey, the failed one at (700, 700) a red cross.
        assert_eq!(pixel(20, 20), [153, 153, 153]);
        assert_eq!(pixel(701, 701), [255, 0, 0]);
        // Far from everything: white.
        assert_eq!(pixel(200, 500), [255, 255, 255]);
        assert!(frame_rgb(&mission, &frame, 10).is_err());
    }

    /// A PNG reads back: its chunks' checksums hold and its zlib stream inflates to the
    /// rows, each after a filter byte of 0.
    #[test]
    fn a_png_reads_back() {
        use std::io::Read as _;
        let size = 64;
        let rgb: Vec<u8> = (0..size * size * 3).map(|i| (i * 7 % 251) as u8).collect();
        let file = png(&rgb, size);
        let (mut at, mut data) = (8, Vec::new());
        while at < file.len() {
            let length = u32::from_be_bytes(file[at..at + 4].try_into().unwrap()) as usize;
            let (kind, body) = (&file[at + 4..at + 8], &file[at + 8..at + 8 + length]);
            let crc =
                u32::from_be_bytes(file[at + 8 + length..at + 12 + length].try_into().unwrap());
            let mut hasher = crc32fast::Hasher::new();
            hasher.update(kind);
            hasher.update(body);
            assert_eq!(hasher.finalize(), crc);
            if kind == b"IDAT" {
                data.extend_from_slice(body);
            }
            at += 12 + length;
        }
        let mut rows = Vec::new();
        flate2::read::ZlibDecoder::new(data.as_slice())
            .read_to_end(&mut rows)
            .unwrap();
        let back: Vec<u8> = rows
            .chunks_exact(size * 3 + 1)
            .flat_map(|r| {
                assert_eq!(r[0], 0);
                r[1..].to_vec()
            })
            .collect();
        assert_eq!(back, rgb);
    }
}
