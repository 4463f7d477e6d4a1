//! The generator of the built-in scenes in `demo/scenes/` (`mcg-demo scenes` rewrites them;
//! a test checks that the committed files equal its output byte for byte).
//!
//! All six are rooms 4 m wide (x ∈ [−2, 2]), 3 m high (y ∈ [0, 3]) and 5 m deep
//! (z ∈ [−2.5, 2.5]), seen by a 60° camera at (0, 1.5, 2.3) looking down −z, with a red left
//! wall, a green right wall and two boxes; all but the last are closed. Each is a `.gltf` with its geometry in a `.bin`
//! next to it (non-indexed triangles, counter-clockwise seen from the front).
//!
//! - `hidden_light_room`: a 1.2 m square light lying in a 2.2 m square tray hung under the
//!   ceiling, facing up; the tray's rim stops 0.25 m below the ceiling, so the light reaches
//!   the room only through that slit, after bouncing off the ceiling above the tray — the
//!   room is lit only indirectly and a light sample from it is occluded (MCPG's case).
//! - `many_lights_room`: 24 small lights of different colours on the ceiling and the back
//!   wall, a polished metal box (direct light from many sources, MCMM's case).
//! - `dynamic_room`: the hidden light room with a doorway in the right wall to a small side
//!   room lit by a warm light. Animations (glTF, [`super::scene::FRAME_RATE`] = 24 frames per
//!   second): the hidden light and its panel slide along x from −1 m to +1 m over frames 0–64
//!   (LINEAR), and the door turns open by 90° about its hinge at frame [`DOOR_OPENS_AT_FRAME`]
//!   (STEP). The scene's `extras.mcg` repeats both facts for readers of the file.
//! - `door_room`: ADGI's Fig. 1 case in miniature — the room lit directly by one
//!   [`DOOR_ROOM_LIGHT_HALF`]·2 m square ceiling light, and behind the closed door of the
//!   right wall a side room lit brightly by a warm light. The door turns open by 90° at frame
//!   [`DOOR_ROOM_OPENS_AT_FRAME`] (STEP) and nothing else moves, so the scene has exactly two
//!   states (door closed, door open).
//! - `sky_room`: no lamp — a 0.6 m × 0.8 m window high in the right wall, out of the camera's
//!   view, opens onto a uniform sky of radiance [`SKY_ROOM_ENVIRONMENT`], which the scene's
//!   `extras.mcg.environment` names (the loader reads it, [`super::scene::SceneFile::open`]):
//!   all light enters through the window, the case of path guiding's interiors lit through an
//!   opening. The extras name the window as a portal too (`mcg.portals`), at which `nee`'s
//!   light samples of the sky aim.
//! - `sun_room`: the sky room under a sky with a sun ([`sun_sky`], written beside it as the
//!   Radiance file [`SUN_SKY_FILE`], which its extras name): the sun shines through the window
//!   onto the floor in view, and light sampling of the map finds the sun, mostly behind the
//!   walls.

use std::path::Path;

use glam::{Quat, Vec3};
use serde_json::{Value, json};

use super::scene::FRAME_RATE;
use crate::Result;

/// The frame at which the door of `dynamic_room` opens.
pub const DOOR_OPENS_AT_FRAME: u32 = 32;
/// The frame at which the moving light of `dynamic_room` reaches its end position.
pub const LIGHT_STOPS_AT_FRAME: u32 = 64;

/// The frame at which the door of `door_room` opens (its only change; late enough that the
/// probes of `adgi` and `ddgi` have converged on the closed room before it).
pub const DOOR_ROOM_OPENS_AT_FRAME: u32 = 32;
/// Half the side of `door_room`'s ceiling light.
pub const DOOR_ROOM_LIGHT_HALF: f32 = 0.25;
/// `KHR_materials_emissive_strength` of `door_room`'s ceiling light.
const DOOR_ROOM_LIGHT_STRENGTH: f32 = 30.0;
/// `KHR_materials_emissive_strength` of `door_room`'s side-room light (the side room is lit
/// more brightly than the main room, so opening the door changes it visibly).
const DOOR_ROOM_SIDE_STRENGTH: f32 = 150.0;
/// `KHR_materials_emissive_strength` of `dynamic_room`'s side-room light.
const DYNAMIC_ROOM_SIDE_STRENGTH: f32 = 60.0;

/// Names of the built-in scenes (file stems under `demo/scenes/`).
pub const SCENE_NAMES: [&str; 6] = [
    "hidden_light_room",
    "many_lights_room",
    "dynamic_room",
    "door_room",
    "sky_room",
    "sun_room",
];

/// The environment map of `sun_room` in `demo/scenes/` ([`sun_sky`], Radiance RGBE).
pub const SUN_SKY_FILE: &str = "sun_room_sky.hdr";

/// The direction toward the sun of [`sun_sky`] (unit): 30° above the horizon, on the side of
/// the rooms' right wall (+x) and behind the camera (+z), so that it shines through
/// `sun_room`'s window onto the floor at the foot of the left box, in view.
pub const SUN_DIRECTION: [f32; 3] = [0.7035, 0.5025, 0.5025];

/// The sun's angular radius in [`sun_sky`]: 2.5° (five times the real sun's, so that its
/// disc covers about 25 texels of the 256 × 128 map).
pub const SUN_RADIUS_DEGREES: f32 = 2.5;

/// The sun's radiance in [`sun_sky`], linear RGB: its disc's irradiance at normal incidence
/// (≈ 6 sr⁻¹·10⁻³ × this ≈ 59) is about five times the sky's.
pub const SUN_RADIANCE: [f32; 3] = [10_000.0, 9_200.0, 8_000.0];

/// `sun_room`'s sky: a 256 × 128 equirectangular map ([`super::environment`]'s
/// conventions) of a blue sky, brighter toward the horizon ((1.5, 2, 4) at the zenith,
/// (4, 4.5, 5.5) at the horizon), a uniform brown ground (0.3, 0.25, 0.2) below the horizon
/// and a sun of [`SUN_RADIANCE`] within [`SUN_RADIUS_DEGREES`] of [`SUN_DIRECTION`]; texel
/// centres decide. Row-major from the top-left, as [`super::environment::EnvironmentMap::new`]
/// takes it.
#[must_use]
pub fn sun_sky() -> (u32, u32, Vec<Vec3>) {
    let (w, h) = (256u32, 128u32);
    let sun = Vec3::from(SUN_DIRECTION).normalize();
    let cos_radius = SUN_RADIUS_DEGREES.to_radians().cos();
    let texels = (0..w * h)
        .map(|i| {
            let uv = glam::Vec2::new(
                ((i % w) as f32 + 0.5) / w as f32,
                ((i / w) as f32 + 0.5) / h as f32,
            );
            let d = super::environment::EnvironmentMap::direction(uv);
            if d.dot(sun) > cos_radius {
                Vec3::from(SUN_RADIANCE)
            } else if d.y < 0.0 {
                Vec3::new(0.3, 0.25, 0.2)
            } else {
                Vec3::new(1.5, 2.0, 4.0) + (1.0 - d.y) * Vec3::new(2.5, 2.5, 1.5)
            }
        })
        .collect();
    (w, h, texels)
}

/// [`sun_sky`] as a Radiance RGBE file (what the `image` crate writes).
///
/// # Panics
/// Never: encoding to memory does not fail.
#[must_use]
pub fn sun_sky_hdr() -> Vec<u8> {
    let (w, h, texels) = sun_sky();
    let pixels: Vec<image::Rgb<f32>> = texels.iter().map(|t| image::Rgb(t.to_array())).collect();
    let mut bytes = Vec::new();
    image::codecs::hdr::HdrEncoder::new(&mut bytes)
        .encode(&pixels, w as usize, h as usize)
        .expect("encoding to memory");
    bytes
}

/// The files of `demo/scenes/` besides the scenes' `.gltf` and `.bin`: `(name, bytes)`.
#[must_use]
pub fn built_in_files() -> Vec<(&'static str, Vec<u8>)> {
    vec![(SUN_SKY_FILE, sun_sky_hdr())]
}

/// The opening of a room's right wall (x = 2 m).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Opening {
    /// A closed wall.
    None,
    /// A doorway 1 m wide and 2.2 m high at z ∈ [−0.5, 0.5] (scenes (c) and (d)).
    Doorway,
    /// A window [`WINDOW`] (`sky_room`).
    Window,
}

/// `sky_room`'s window in the right wall: z from 0 to 0.6 m, y from 1.4 to 2.2 m.
const WINDOW: (f32, f32, f32, f32) = (0.0, 0.6, 1.4, 2.2);

/// The window as the portal the sky and sun rooms' extras name (`mcg.portals`: a corner and
/// two edges, [`super::environment::Portal`]), in the right wall's plane x = 2 m.
fn window_portal() -> Value {
    let (z0, z1, y0, y1) = WINDOW;
    json!([[2.0, y0, z0, 0.0, 0.0, z1 - z0, 0.0, y1 - y0, 0.0]])
}

/// The sky's radiance in `sky_room` (linear RGB, a pale blue).
pub const SKY_ROOM_ENVIRONMENT: [f32; 3] = [4.0, 4.5, 5.5];

/// A material of the generator: glTF metallic-roughness factors and emission.
#[derive(Clone, Copy)]
struct Mat {
    name: &'static str,
    base: [f32; 3],
    metallic: f32,
    roughness: f32,
    emissive: [f32; 3],
    strength: f32,
}

const fn diffuse(name: &'static str, base: [f32; 3]) -> Mat {
    Mat {
        name,
        base,
        metallic: 0.0,
        roughness: 1.0,
        emissive: [0.0; 3],
        strength: 1.0,
    }
}

const fn light(name: &'static str, colour: [f32; 3], strength: f32) -> Mat {
    Mat {
        name,
        base: [0.0; 3],
        metallic: 0.0,
        roughness: 1.0,
        emissive: colour,
        strength,
    }
}

const WHITE: Mat = diffuse("white", [0.75, 0.75, 0.75]);
const RED: Mat = diffuse("red", [0.63, 0.08, 0.06]);
const GREEN: Mat = diffuse("green", [0.12, 0.45, 0.1]);
const FLOOR: Mat = diffuse("floor", [0.55, 0.5, 0.45]);
const PANEL: Mat = diffuse("panel", [0.7, 0.7, 0.7]);

/// One mesh: triangles of one material, placed by a node.
struct Part {
    material: Mat,
    triangles: Vec<[Vec3; 3]>,
}

/// Two triangles of the parallelogram `p, p + u, p + u + v, p + v`; front face along `u × v`.
fn quad(out: &mut Vec<[Vec3; 3]>, p: Vec3, u: Vec3, v: Vec3) {
    out.push([p, p + u, p + u + v]);
    out.push([p, p + u + v, p + v]);
}

/// The six faces of the box `[lo, hi]`, front faces outwards.
fn cuboid(out: &mut Vec<[Vec3; 3]>, lo: Vec3, hi: Vec3) {
    let d = hi - lo;
    let (x, y, z) = (Vec3::X * d.x, Vec3::Y * d.y, Vec3::Z * d.z);
    quad(out, lo, z, y); // −x
    quad(out, lo + x, y, z); // +x
    quad(out, lo, x, z); // −y
    quad(out, lo + y, z, x); // +y
    quad(out, lo, y, x); // −z
    quad(out, lo + z, x, y); // +z
}

fn part(material: Mat, triangles: Vec<[Vec3; 3]>) -> Part {
    Part {
        material,
        triangles,
    }
}

/// The room's shell (front faces inwards) with `opening` in the right wall, and the two
/// boxes.
fn room(opening: Opening) -> Vec<Part> {
    let (w, h, d) = (2.0, 3.0, 2.5);
    let mut floor = Vec::new();
    quad(
        &mut floor,
        Vec3::new(-w, 0.0, -d),
        Vec3::Z * 2.0 * d,
        Vec3::X * 2.0 * w,
    );
    let mut white = Vec::new();
    quad(
        &mut white,
        Vec3::new(-w, h, -d),
        Vec3::X * 2.0 * w,
        Vec3::Z * 2.0 * d,
    ); // ceiling
    quad(
        &mut white,
        Vec3::new(-w, 0.0, -d),
        Vec3::X * 2.0 * w,
        Vec3::Y * h,
    ); // back
    quad(
        &mut white,
        Vec3::new(-w, 0.0, d),
        Vec3::Y * h,
        Vec3::X * 2.0 * w,
    ); // front
    let mut red = Vec::new();
    quad(
        &mut red,
        Vec3::new(-w, 0.0, -d),
        Vec3::Y * h,
        Vec3::Z * 2.0 * d,
    );
    let mut green = Vec::new();
    let right = |out: &mut Vec<[Vec3; 3]>, z0: f32, z1: f32, y0: f32, y1: f32| {
        quad(
            out,
            Vec3::new(w, y0, z0),
            Vec3::Z * (z1 - z0),
            Vec3::Y * (y1 - y0),
        );
    };
    match opening {
        Opening::None => right(&mut green, -d, d, 0.0, h),
        Opening::Doorway => {
            right(&mut green, -d, -0.5, 0.0, h);
            right(&mut green, 0.5, d, 0.0, h);
            right(&mut green, -0.5, 0.5, 2.2, h);
        }
        Opening::Window => {
            let (z0, z1, y0, y1) = WINDOW;
            right(&mut green, -d, z0, 0.0, h);
            right(&mut green, z1, d, 0.0, h);
            right(&mut green, z0, z1, 0.0, y0);
            right(&mut green, z0, z1, y1, h);
        }
    }
    let mut boxes = Vec::new();
    cuboid(
        &mut boxes,
        Vec3::new(-1.4, 0.0, -1.6),
        Vec3::new(-0.5, 1.4, -0.7),
    );
    cuboid(
        &mut boxes,
        Vec3::new(0.5, 0.0, -0.6),
        Vec3::new(1.3, 0.8, 0.2),
    );
    vec![
        part(FLOOR, floor),
        part(WHITE, white),
        part(RED, red),
        part(GREEN, green),
        part(WHITE, boxes),
    ]
}

/// The hidden light (facing up) and its panel, centred on x = 0 in the node's frame.
fn hidden_light() -> Vec<Part> {
    let mut lamp = Vec::new();
    quad(
        &mut lamp,
        Vec3::new(-0.15, 2.3, -0.15),
        Vec3::Z * 0.3,
        Vec3::X * 0.3,
    );
    let mut panel = Vec::new();
    cuboid(
        &mut panel,
        Vec3::new(-0.6, 2.2, -0.6),
        Vec3::new(0.6, 2.25, 0.6),
    );
    vec![
        part(light("hidden_light", [1.0, 0.95, 0.85], 400.0), lamp),
        part(PANEL, panel),
    ]
}

/// The light of `hidden_light_room`: a [`COVE_LIGHT_HALF`]·2 m square light lying in a tray
/// (a [`COVE_HALF`]·2 m square panel at height [`COVE_PANEL_Y`] with a rim) facing up. The
/// rim stops [`COVE_SLIT`] below the ceiling: the light shines on the ceiling above the tray,
/// and the room receives it only through the slit, after at least one bounce in the cove — a
/// light sample from the room is occluded, and the light reaches the camera after two or more
/// scattering events. The camera (at 1.5 m) sees the tray's underside, not into the cove.
fn cove_light() -> Vec<Part> {
    let (y_panel, thickness, half, z_centre) = (COVE_PANEL_Y, 0.05, COVE_HALF, -0.5);
    let l = COVE_LIGHT_HALF;
    let mut lamp = Vec::new();
    quad(
        &mut lamp,
        Vec3::new(-l, y_panel + thickness + 0.001, z_centre - l),
        Vec3::Z * 2.0 * l,
        Vec3::X * 2.0 * l,
    );
    let mut panel = Vec::new();
    cuboid(
        &mut panel,
        Vec3::new(-half, y_panel, z_centre - half),
        Vec3::new(half, y_panel + thickness, z_centre + half),
    );
    // The rim: four walls on the panel's edges, up to COVE_SLIT under the ceiling.
    let top = 3.0 - COVE_SLIT;
    let (lo, hi) = (z_centre - half, z_centre + half);
    for (a, b) in [
        (
            Vec3::new(-half, y_panel, lo),
            Vec3::new(half, top, lo + thickness),
        ),
        (
            Vec3::new(-half, y_panel, hi - thickness),
            Vec3::new(half, top, hi),
        ),
        (
            Vec3::new(-half, y_panel, lo),
            Vec3::new(-half + thickness, top, hi),
        ),
        (
            Vec3::new(half - thickness, y_panel, lo),
            Vec3::new(half, top, hi),
        ),
    ] {
        cuboid(&mut panel, a, b);
    }
    vec![
        part(
            light("hidden_light", [1.0, 0.95, 0.85], COVE_STRENGTH),
            lamp,
        ),
        part(PANEL, panel),
    ]
}

/// Height of the underside of the tray of `hidden_light_room` (the ceiling is at 3 m).
const COVE_PANEL_Y: f32 = 2.55;
/// Half the side of the tray.
const COVE_HALF: f32 = 1.1;
/// Half the side of the light in the tray.
const COVE_LIGHT_HALF: f32 = 0.6;
/// `KHR_materials_emissive_strength` of the light.
const COVE_STRENGTH: f32 = 60.0;
/// The gap between the tray's rim and the ceiling.
const COVE_SLIT: f32 = 0.25;

/// A node: the parts it carries and its translation; `animated` nodes get animation channels.
struct Node {
    name: &'static str,
    parts: Vec<Part>,
    translation: Vec3,
}

/// An animation channel: node index, property, keyframe times and values (3 or 4 wide).
struct Channel {
    node: usize,
    path: &'static str,
    step: bool,
    times: Vec<f32>,
    values: Vec<Vec<f32>>,
}

/// The binary buffer of a glTF file with its buffer views and accessors.
#[derive(Default)]
struct GltfBuffer {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl GltfBuffer {
    /// Appends `data` as little-endian f32 with a view and an accessor of `count` elements of
    /// `kind` (`"VEC3"`, …) and optional (min, max); returns the accessor's index.
    fn push_floats(
        &mut self,
        data: &[f32],
        kind: &str,
        count: usize,
        bounds: Option<(Value, Value)>,
    ) -> usize {
        let offset = self.bin.len();
        for f in data {
            self.bin.extend_from_slice(&f.to_le_bytes());
        }
        self.views
            .push(json!({ "buffer": 0, "byteOffset": offset, "byteLength": data.len() * 4 }));
        let mut accessor = json!({
            "bufferView": self.views.len() - 1, "componentType": 5126, "count": count, "type": kind,
        });
        if let Some((min, max)) = bounds {
            accessor["min"] = min;
            accessor["max"] = max;
        }
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    /// A part's triangles as a POSITION accessor with its bounds.
    fn push_positions(&mut self, p: &Part) -> usize {
        let flat: Vec<f32> = p
            .triangles
            .iter()
            .flatten()
            .flat_map(|v| v.to_array())
            .collect();
        let lo = p
            .triangles
            .iter()
            .flatten()
            .fold(Vec3::INFINITY, |a, &b| a.min(b));
        let hi = p
            .triangles
            .iter()
            .flatten()
            .fold(Vec3::NEG_INFINITY, |a, &b| a.max(b));
        self.push_floats(
            &flat,
            "VEC3",
            p.triangles.len() * 3,
            Some((json!(lo.to_array()), json!(hi.to_array()))),
        )
    }
}

/// A material as glTF metallic-roughness, emissive ones with `KHR_materials_emissive_strength`.
fn material_json(m: &Mat) -> Value {
    let mut material = json!({
        "name": m.name,
        "pbrMetallicRoughness": {
            "baseColorFactor": [m.base[0], m.base[1], m.base[2], 1.0],
            "metallicFactor": m.metallic,
            "roughnessFactor": m.roughness,
        },
    });
    if m.emissive != [0.0; 3] {
        material["emissiveFactor"] = json!(m.emissive);
        material["extensions"] = json!({
            "KHR_materials_emissive_strength": { "emissiveStrength": m.strength }
        });
    }
    material
}

/// The animation samplers and channels of `channels`, their keys appended to `buffer`.
fn animation_json(buffer: &mut GltfBuffer, channels: &[Channel]) -> (Vec<Value>, Vec<Value>) {
    let mut samplers = Vec::new();
    let mut gltf_channels = Vec::new();
    for c in channels {
        let input = buffer.push_floats(
            &c.times,
            "SCALAR",
            c.times.len(),
            Some((json!([c.times[0]]), json!([c.times[c.times.len() - 1]]))),
        );
        let flat: Vec<f32> = c.values.iter().flatten().copied().collect();
        let kind = if c.values[0].len() == 4 {
            "VEC4"
        } else {
            "VEC3"
        };
        let output = buffer.push_floats(&flat, kind, c.values.len(), None);
        samplers.push(json!({
            "input": input, "output": output,
            "interpolation": if c.step { "STEP" } else { "LINEAR" },
        }));
        gltf_channels.push(
            json!({ "sampler": samplers.len() - 1, "target": { "node": c.node, "path": c.path } }),
        );
    }
    (samplers, gltf_channels)
}

/// Serialises nodes, channels and scene extras into glTF JSON and its binary buffer.
fn write_gltf(
    name: &str,
    nodes: &[Node],
    channels: &[Channel],
    extras: Value,
) -> (String, Vec<u8>) {
    let mut buffer = GltfBuffer::default();
    let mut materials = Vec::new();
    let mut meshes = Vec::new();
    let mut gltf_nodes = Vec::new();
    for node in nodes {
        let mut primitives = Vec::new();
        for p in &node.parts {
            let position = buffer.push_positions(p);
            materials.push(material_json(&p.material));
            primitives.push(
                json!({ "attributes": { "POSITION": position }, "material": materials.len() - 1 }),
            );
        }
        meshes.push(json!({ "name": node.name, "primitives": primitives }));
        let mut n = json!({ "name": node.name, "mesh": meshes.len() - 1 });
        if node.translation != Vec3::ZERO {
            n["translation"] = json!(node.translation.to_array());
        }
        gltf_nodes.push(n);
    }
    // The camera: 60° vertical field of view, at (0, 1.5, 2.3), looking down −z (no rotation).
    gltf_nodes.push(json!({ "name": "camera", "camera": 0, "translation": [0.0, 1.5, 2.3] }));
    let (samplers, gltf_channels) = animation_json(&mut buffer, channels);
    let GltfBuffer {
        bin,
        views,
        accessors,
    } = buffer;
    let mut doc = json!({
        "asset": { "version": "2.0", "generator": "mcg-demo scene_generator" },
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{
            "name": name,
            "nodes": (0..gltf_nodes.len()).collect::<Vec<_>>(),
            "extras": { "mcg": extras },
        }],
        "nodes": gltf_nodes,
        "cameras": [{ "type": "perspective", "perspective": { "yfov": 60f32.to_radians(), "znear": 0.01 } }],
        "meshes": meshes,
        "materials": materials,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{ "uri": format!("{name}.bin"), "byteLength": bin.len() }],
    });
    if !gltf_channels.is_empty() {
        doc["animations"] =
            json!([{ "name": "motion", "samplers": samplers, "channels": gltf_channels }]);
    }
    let mut text = serde_json::to_string_pretty(&doc).expect("JSON values serialise");
    text.push('\n');
    (text, bin)
}

/// The built-in scenes: `(name, glTF JSON, binary buffer)` each, in [`SCENE_NAMES`] order.
#[must_use]
pub fn built_in_scenes() -> Vec<(&'static str, String, Vec<u8>)> {
    let (a_json, a_bin) = hidden_light_scene();
    let (b_json, b_bin) = many_lights_scene();
    let (c_json, c_bin) = dynamic_scene();
    let (d_json, d_bin) = door_scene();
    let (e_json, e_bin) = sky_room_scene();
    let (f_json, f_bin) = sun_room_scene();
    vec![
        (SCENE_NAMES[0], a_json, a_bin),
        (SCENE_NAMES[1], b_json, b_bin),
        (SCENE_NAMES[2], c_json, c_bin),
        (SCENE_NAMES[3], d_json, d_bin),
        (SCENE_NAMES[4], e_json, e_bin),
        (SCENE_NAMES[5], f_json, f_bin),
    ]
}

/// (e) The room with a window in its right wall open onto a uniform sky, and no lamp.
fn sky_room_scene() -> (String, Vec<u8>) {
    write_gltf(
        SCENE_NAMES[4],
        &[static_node(room(Opening::Window))],
        &[],
        json!({
            "description": "a room lit only by a uniform sky through a window",
            "environment": SKY_ROOM_ENVIRONMENT,
            "portals": window_portal(),
        }),
    )
}

/// (f) The sky room under [`sun_sky`]: a sun shines through the window.
fn sun_room_scene() -> (String, Vec<u8>) {
    write_gltf(
        SCENE_NAMES[5],
        &[static_node(room(Opening::Window))],
        &[],
        json!({
            "description": "a room lit only by a sky and a sun through a window",
            "environment": SUN_SKY_FILE,
        }),
    )
}

/// The room as one static node.
fn static_node(parts: Vec<Part>) -> Node {
    Node {
        name: "room",
        parts,
        translation: Vec3::ZERO,
    }
}

/// (a) Hidden light: a closed room lit through a slit by a light in a tray under the ceiling.
fn hidden_light_scene() -> (String, Vec<u8>) {
    let mut parts = room(Opening::None);
    parts.extend(cove_light());
    write_gltf(
        SCENE_NAMES[0],
        &[static_node(parts)],
        &[],
        json!({ "description": "a closed room lit through a slit by a light hidden in a tray under the ceiling" }),
    )
}

/// (b) Many lights: 4×4 on the ceiling, 8 on the back wall, colours around the hue circle, and
/// a copper block.
fn many_lights_scene() -> (String, Vec<u8>) {
    let mut parts = room(Opening::None);
    let mut k = 0;
    let colour = |k: usize| {
        let hue = k as f32 / 24.0 * core::f32::consts::TAU;
        let c =
            Vec3::new(hue.cos(), (hue - 2.094).cos(), (hue + 2.094).cos()) * 0.5 + Vec3::splat(0.5);
        (c / c.max_element()).to_array()
    };
    for i in 0..4 {
        for j in 0..4 {
            let mut tris = Vec::new();
            let p = Vec3::new(-1.5 + i as f32, 2.999, -2.0 + 1.2 * j as f32);
            quad(&mut tris, p, Vec3::X * 0.12, Vec3::Z * 0.12); // faces down
            parts.push(part(light("ceiling_light", colour(k), 60.0), tris));
            k += 1;
        }
    }
    for i in 0..8 {
        let mut tris = Vec::new();
        let p = Vec3::new(-1.75 + 0.5 * i as f32, 1.0 + 0.8 * (i % 2) as f32, -2.499);
        quad(&mut tris, p, Vec3::X * 0.1, Vec3::Y * 0.1); // faces +z, into the room
        parts.push(part(light("wall_light", colour(k), 60.0), tris));
        k += 1;
    }
    let mut metal = Vec::new();
    cuboid(
        &mut metal,
        Vec3::new(-0.3, 0.0, 0.6),
        Vec3::new(0.3, 0.6, 1.2),
    );
    parts.push(part(
        Mat {
            name: "metal",
            base: [0.95, 0.64, 0.54],
            metallic: 1.0,
            roughness: 0.3,
            emissive: [0.0; 3],
            strength: 1.0,
        },
        metal,
    ));
    write_gltf(
        SCENE_NAMES[1],
        &[static_node(parts)],
        &[],
        json!({ "description": "a closed room lit directly by 24 small lights of different colours" }),
    )
}

/// The lit side room behind the doorway (walls and a light of `strength`) and the door, a
/// node hinged at (2, 0, −0.5) that [`door_channel`] turns open.
fn side_room_and_door(strength: f32) -> (Vec<Part>, Node) {
    let mut lamp = Vec::new();
    quad(
        &mut lamp,
        Vec3::new(2.6, 2.999, -0.2),
        Vec3::X * 0.4,
        Vec3::Z * 0.4,
    );
    let parts = vec![
        part(WHITE, side_room()),
        part(light("side_light", [1.0, 0.7, 0.4], strength), lamp),
    ];
    let mut door = Vec::new();
    cuboid(
        &mut door,
        Vec3::new(-0.025, 0.0, 0.0),
        Vec3::new(0.025, 2.2, 1.0),
    );
    let node = Node {
        name: "door",
        parts: vec![part(PANEL, door)],
        translation: Vec3::new(2.0, 0.0, -0.5),
    };
    (parts, node)
}

/// The STEP channel that turns node `node` (the door) by 90° about +y at frame `frame`.
fn door_channel(node: usize, frame: u32) -> Channel {
    let open = Quat::from_rotation_y(core::f32::consts::FRAC_PI_2)
        .to_array()
        .to_vec();
    Channel {
        node,
        path: "rotation",
        step: true,
        times: vec![0.0, frame as f32 / FRAME_RATE],
        values: vec![vec![0.0, 0.0, 0.0, 1.0], open],
    }
}

/// (c) Dynamic: the moving hidden light and a door to a lit side room opening at a known frame.
fn dynamic_scene() -> (String, Vec<u8>) {
    let mut parts = room(Opening::Doorway);
    let (side, door) = side_room_and_door(DYNAMIC_ROOM_SIDE_STRENGTH);
    parts.extend(side);
    let nodes = [
        static_node(parts),
        Node {
            name: "moving_light",
            parts: hidden_light(),
            translation: Vec3::new(-1.0, 0.0, 0.0),
        },
        door,
    ];
    let channels = [
        Channel {
            node: 1,
            path: "translation",
            step: false,
            times: vec![0.0, LIGHT_STOPS_AT_FRAME as f32 / FRAME_RATE],
            values: vec![vec![-1.0, 0.0, 0.0], vec![1.0, 0.0, 0.0]],
        },
        door_channel(2, DOOR_OPENS_AT_FRAME),
    ];
    write_gltf(
        SCENE_NAMES[2],
        &nodes,
        &channels,
        json!({
            "description": "the hidden light room with a moving light and a door to a lit side room",
            "frame_rate": FRAME_RATE,
            "door_opens_at_frame": DOOR_OPENS_AT_FRAME,
            "light_moves_until_frame": LIGHT_STOPS_AT_FRAME,
        }),
    )
}

/// (d) Door: a room lit directly by one ceiling light, and a door to a brightly lit side room
/// that opens at [`DOOR_ROOM_OPENS_AT_FRAME`] — the only change (ADGI Fig. 1's gate).
fn door_scene() -> (String, Vec<u8>) {
    let mut parts = room(Opening::Doorway);
    let (side, door) = side_room_and_door(DOOR_ROOM_SIDE_STRENGTH);
    parts.extend(side);
    let l = DOOR_ROOM_LIGHT_HALF;
    let mut lamp = Vec::new();
    quad(
        &mut lamp,
        Vec3::new(-l, 2.999, -0.5 - l),
        Vec3::X * 2.0 * l,
        Vec3::Z * 2.0 * l,
    ); // faces down
    parts.push(part(
        light("ceiling_light", [1.0, 0.95, 0.85], DOOR_ROOM_LIGHT_STRENGTH),
        lamp,
    ));
    write_gltf(
        SCENE_NAMES[3],
        &[static_node(parts), door],
        &[door_channel(1, DOOR_ROOM_OPENS_AT_FRAME)],
        json!({
            "description": "a room lit by one ceiling light and a door to a brightly lit side room",
            "frame_rate": FRAME_RATE,
            "door_opens_at_frame": DOOR_ROOM_OPENS_AT_FRAME,
        }),
    )
}

/// The white side room of scenes (c) and (d) behind the door: floor, ceiling and three walls.
fn side_room() -> Vec<[Vec3; 3]> {
    let mut side = Vec::new();
    let (x0, x1, z0, z1, h) = (2.0, 3.5, -1.0, 1.0, 3.0);
    quad(
        &mut side,
        Vec3::new(x0, 0.0, z0),
        Vec3::Z * (z1 - z0),
        Vec3::X * (x1 - x0),
    ); // floor
    quad(
        &mut side,
        Vec3::new(x0, h, z0),
        Vec3::X * (x1 - x0),
        Vec3::Z * (z1 - z0),
    ); // ceiling
    quad(
        &mut side,
        Vec3::new(x1, 0.0, z0),
        Vec3::Z * (z1 - z0),
        Vec3::Y * h,
    ); // far wall
    quad(
        &mut side,
        Vec3::new(x0, 0.0, z0),
        Vec3::X * (x1 - x0),
        Vec3::Y * h,
    ); // z0 wall
    quad(
        &mut side,
        Vec3::new(x0, 0.0, z1),
        Vec3::Y * h,
        Vec3::X * (x1 - x0),
    ); // z1 wall
    side
}

/// Writes the built-in scenes as `<name>.gltf` + `<name>.bin` into `dir` (created if missing).
///
/// # Errors
/// When a file cannot be written.
pub fn write_built_in_scenes(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let write = |file: &str, bytes: &[u8]| {
        let path = dir.join(file);
        std::fs::write(&path, bytes).map_err(|e| format!("cannot write {}: {e}", path.display()))
    };
    for (name, text, bin) in built_in_scenes() {
        write(&format!("{name}.gltf"), text.as_bytes())?;
        write(&format!("{name}.bin"), &bin)?;
    }
    for (file, bytes) in built_in_files() {
        write(file, &bytes)?;
    }
    Ok(())
}
