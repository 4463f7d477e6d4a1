//! Per-state references of an animated scene and the errors of each frame against the
//! reference of its own state (`--reference-spp`).
//!
//! A scene's *state* is its geometry at a frame: frames whose triangles are bit-identical
//! share a state (a STEP animation has one state per step; a LINEAR one a state per frame).
//! Each state gets one `nee` reference, rendered once and cached under
//! `<out>/reference/` by scene, size, bounces, samples and the state's [`Scene::fingerprint`].
//! The **event** is the first change of state; the **event region** the pixels whose
//! references before and after it differ ([`event_mask`]). A real-time method shows each
//! frame on its own, so each frame's own image is compared with its state's reference
//! (relative MSE, [`super::output::errors`]) over the whole image and over the event region.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::Vec3;

use super::cpu::{BsdfSampler, Method, RenderSettings, render_frame};
use super::output::{Errors, RgbImage, errors};
use super::scene::{Scene, SceneFile, frame_time};
use crate::Result;

/// The seed of every state reference (fixed, so renders of any seed share the cached files).
pub const REFERENCE_SEED: u32 = 0x00ef_e7e5;

/// A pixel is in the event region when the luminances `a`, `b` of the two references differ
/// by more than this fraction of `max(a, b) + EVENT_LUMINANCE_FLOOR`.
pub const EVENT_RELATIVE_CHANGE: f32 = 0.2;

/// The floor added to the larger luminance in [`EVENT_RELATIVE_CHANGE`]'s test, so that the
/// noise of nearly black pixels does not put them in the event region (the scale of
/// relMSE's ε: `√ε` = 0.1).
pub const EVENT_LUMINANCE_FLOOR: f32 = 0.1;

/// The default of `--event-error-threshold`: the event region's relMSE that
/// [`DynamicErrors::frames_to_threshold`] waits for.
pub const DEFAULT_EVENT_ERROR_THRESHOLD: f64 = 0.05;

/// What a render with `--reference-spp` records besides the whole-image errors of each frame
/// (the `dynamic` object of `<method>.json`).
#[derive(Clone, Debug, serde::Serialize)]
pub struct DynamicErrors {
    /// The reference of each state, in order of first appearance.
    pub references: Vec<PathBuf>,
    /// For each frame, the index of its state in `references`.
    pub state_of_frame: Vec<u32>,
    /// The first frame whose state differs from frame 0's (`None` for a static scene).
    pub event_frame: Option<u32>,
    /// [`EVENT_RELATIVE_CHANGE`].
    pub event_relative_change: f32,
    /// Pixels in the event region.
    pub event_pixels: usize,
    /// Errors of each frame's own image over the event region (empty without an event).
    pub event_errors: Vec<Errors>,
    /// The relMSE threshold of `frames_to_threshold` (`--event-error-threshold`).
    pub error_threshold: f64,
    /// Frames from the event until the event region's relMSE first falls to the threshold or
    /// below (0: at the event frame itself); `None` if it never does or there is no event.
    pub frames_to_threshold: Option<u32>,
}

/// The states of a render's frames and their references.
#[derive(Debug)]
pub struct SceneStates {
    references: Vec<RgbImage>,
    state_of_frame: Vec<u32>,
    mask: Vec<bool>,
    record: DynamicErrors,
}

/// The scene's state: [`Scene::fingerprint`] (frames of equal fingerprints share a state
/// and a reference; a moving camera or light makes a new one).
fn state_hash(scene: &Scene) -> u64 {
    scene.fingerprint()
}

/// Settings of the state references: size, samples per pixel and bounces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReferenceSettings {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Scattering events per path.
    pub bounces: u32,
}

/// The reference of `scene` (state hash `hash`): read from `dir` when cached, else rendered
/// with `nee` and written there.
fn state_reference(
    scene: &Scene,
    stem: &str,
    hash: u64,
    s: ReferenceSettings,
    dir: &Path,
) -> Result<(PathBuf, RgbImage)> {
    let path = dir.join(format!(
        "{stem}_{}x{}_b{}_nee_{}spp_state{hash:016x}.exr",
        s.width, s.height, s.bounces, s.spp
    ));
    if path.exists() {
        return Ok((path.clone(), RgbImage::read_exr(&path)?));
    }
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let settings = RenderSettings {
        width: s.width,
        height: s.height,
        spp: s.spp,
        bounces: s.bounces,
        seed: REFERENCE_SEED,
        method: Method::Nee,
    };
    let image = RgbImage {
        width: s.width,
        height: s.height,
        pixels: render_frame(scene, &settings, 0, || BsdfSampler, || ()),
    };
    image.write_exr(&path)?;
    Ok((path, image))
}

/// Pixels whose luminances in `a` and `b` differ by more than [`EVENT_RELATIVE_CHANGE`] of
/// the larger plus [`EVENT_LUMINANCE_FLOOR`].
#[must_use]
pub fn event_mask(a: &[Vec3], b: &[Vec3]) -> Vec<bool> {
    let lum = |c: Vec3| c.dot(Vec3::new(0.2126, 0.7152, 0.0722));
    a.iter()
        .zip(b)
        .map(|(&x, &y)| {
            let (lx, ly) = (lum(x), lum(y));
            (lx - ly).abs() > EVENT_RELATIVE_CHANGE * (lx.max(ly) + EVENT_LUMINANCE_FLOOR)
        })
        .collect()
}

/// [`errors`] over the pixels where `mask` is true; `None` when there are none.
#[must_use]
pub fn masked_errors(image: &[Vec3], reference: &[Vec3], mask: &[bool]) -> Option<Errors> {
    let pick = |v: &[Vec3]| -> Vec<Vec3> {
        v.iter()
            .zip(mask)
            .filter_map(|(p, &m)| m.then_some(*p))
            .collect()
    };
    errors(&pick(image), &pick(reference))
}

impl SceneStates {
    /// The states of frames `0..frames` of `file` and their references (cached in
    /// `<out>/reference/`), with `error_threshold` for [`DynamicErrors::frames_to_threshold`].
    ///
    /// # Errors
    /// Scene errors, and when a reference cannot be read or written.
    pub fn new(
        file: &SceneFile,
        frames: u32,
        settings: ReferenceSettings,
        out: &Path,
        error_threshold: f64,
    ) -> Result<Self> {
        let stem = file
            .path()
            .file_stem()
            .and_then(|n| n.to_str())
            .unwrap_or("scene")
            .to_owned();
        let dir = out.join("reference");
        let mut index: HashMap<u64, u32> = HashMap::new();
        let (mut references, mut paths, mut state_of_frame) = (Vec::new(), Vec::new(), Vec::new());
        let mut last = None;
        for frame in 0..frames {
            if frame > 0 && !file.is_animated() {
                state_of_frame.push(0);
                continue;
            }
            let scene = file.build(frame_time(frame))?;
            let hash = state_hash(&scene);
            if last == Some(hash) {
                state_of_frame.push(*state_of_frame.last().unwrap_or(&0));
                continue;
            }
            last = Some(hash);
            let next = index.len() as u32;
            let state = *index.entry(hash).or_insert(next);
            if state == next {
                let (path, image) = state_reference(&scene, &stem, hash, settings, &dir)?;
                paths.push(path);
                references.push(image);
            }
            state_of_frame.push(state);
        }
        let event_frame = state_of_frame
            .iter()
            .position(|&s| s != 0)
            .map(|f| f as u32);
        let mask = match event_frame {
            Some(f) => event_mask(
                &references[0].pixels,
                &references[state_of_frame[f as usize] as usize].pixels,
            ),
            None => Vec::new(),
        };
        let record = DynamicErrors {
            references: paths,
            state_of_frame: state_of_frame.clone(),
            event_frame,
            event_relative_change: EVENT_RELATIVE_CHANGE,
            event_pixels: mask.iter().filter(|&&m| m).count(),
            event_errors: Vec::new(),
            error_threshold,
            frames_to_threshold: None,
        };
        Ok(Self {
            references,
            state_of_frame,
            mask,
            record,
        })
    }

    /// The errors of frame `frame`'s own `image` against its state's reference (whole image);
    /// records the event region's errors as well.
    pub fn frame_errors(&mut self, frame: u32, image: &[Vec3]) -> Option<Errors> {
        let state = *self.state_of_frame.get(frame as usize)? as usize;
        let reference = &self.references[state].pixels;
        if let Some(e) = masked_errors(image, reference, &self.mask) {
            self.record.event_errors.push(e);
        }
        errors(image, reference)
    }

    /// The reference pixels of frame `frame`'s state and the event region's mask (empty for
    /// a scene without an event).
    ///
    /// # Panics
    /// If `frame` is not below the frame count given to [`Self::new`].
    #[must_use]
    pub fn reference_and_mask(&self, frame: u32) -> (&[Vec3], &[bool]) {
        let state = self.state_of_frame[frame as usize] as usize;
        (&self.references[state].pixels, &self.mask)
    }

    /// What was recorded, with `frames_to_threshold` filled in.
    #[must_use]
    pub fn finish(mut self) -> DynamicErrors {
        let r = &mut self.record;
        r.frames_to_threshold = r.event_frame.and_then(|f| {
            r.event_errors
                .iter()
                .skip(f as usize)
                .position(|e| e.rel_mse <= r.error_threshold)
                .map(|k| k as u32)
        });
        self.record
    }
}
