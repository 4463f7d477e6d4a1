//! glTF 2.0 scenes: loading, animation, and the traceable [`Scene`] built from them.
//!
//! What is read (everything else in a file is ignored):
//!
//! - **Geometry**: every triangle primitive (`mode` TRIANGLES, TRIANGLE_STRIP or
//!   TRIANGLE_FAN, with or without indices) of every mesh node of the default scene (or the
//!   first scene), with the node's world transform. Points and lines have no area to hit:
//!   they are skipped, and [`Scene::warnings`] names their meshes. A transform that mirrors
//!   (negative determinant) swaps the winding back, as the glTF 2.0 specification requires
//!   (section "Transformations"), so front faces stay front faces. Shading normals are not
//!   used: shading uses the geometric normal. `TEXCOORD_0` is read for textured materials.
//! - **Camera**: the first node of the default scene, depth first, that carries a
//!   perspective camera; it looks down its local −Z with +Y up (glTF 2.0 specification,
//!   section "Cameras"). `yfov` is used; the aspect ratio is the image's. A file without one
//!   is an error, unless [`SceneFile::with_auto_camera`] (`render --auto-camera`) places one;
//!   [`SceneFile::with_camera`] (`render --camera`) replaces it with one looking at a point.
//! - **Materials** ([`Material`]): `baseColorFactor` (RGB), `metallicFactor`,
//!   `roughnessFactor`, `emissiveFactor × KHR_materials_emissive_strength`, and the
//!   base-colour, emissive and metallic-roughness textures (8-bit PNG or JPEG, `TEXCOORD_0`,
//!   `KHR_texture_transform`, nearest texel, the sampler's wrap modes — its filters are not
//!   read), which multiply `baseColorFactor` and the emission (sRGB-decoded), and
//!   `roughnessFactor` (green) and `metallicFactor` (blue; both linear). Light sampling picks emitting triangles by area ×
//!   the luminance of their emission, textured where they have an emissive texture
//!   ([`Scene::weigh_emitters_by_texture`]); within a triangle it samples area uniformly, so
//!   a dark part of a triangle's texture is sampled as often as a bright one (unbiased, only
//!   less efficient).
//!   A texture on another coordinate set is ignored, and [`Scene::warnings`] says so.
//!   Vertex colours (`COLOR_0`, linear RGB) multiply the base colour.
//! - **Alpha** (glTF 2.0, "Alpha Coverage"): `alphaMode` MASK cuts holes where
//!   `baseColorFactor`'s alpha × the base-colour texture's × `COLOR_0`'s is below
//!   `alphaCutoff` (default ½; [`Material::alpha_cutoff`]): rays pass through them, both when
//!   looking for the closest hit and for occlusion, and they neither reflect nor emit
//!   ([`Scene::is_surface_at`]); a mask that no texel can pass is not loaded. BLEND is
//!   rendered opaque, with a warning.
//! - **Lights** (`KHR_lights_punctual`): a point light becomes a small emitting sphere (an
//!   icosahedron of [`POINT_LIGHT_RADIUS`] × the scene's diagonal) with the light's power, so
//!   that every method can hit it; spot and directional lights are not rendered, with a
//!   warning.
//! - Normal and occlusion textures and extensions other than [`READ_EXTENSIONS`] are not read;
//!   [`Scene::warnings`] names those that change what a surface looks like (all but normal
//!   and occlusion textures).
//! - **Animations**: translation, rotation and scale channels with STEP or LINEAR
//!   interpolation (rotations LINEAR by normalised lerp of the quaternions), evaluated at
//!   the time of the frame ([`frame_time`]); the dynamic built-in scene uses them. Other
//!   channels (CUBICSPLINE, morph-target weights, nodes given as a matrix) are not played:
//!   their nodes keep their rest transforms, and [`Scene::warnings`] says so. Skins are not
//!   read: a skinned mesh is placed by its node's transform, without its joints' deformation.
//!
//! Conventions (glTF 2.0): metres, radians, linear scene-referred RGB radiance; emission from
//! the front face only (counter-clockwise winding seen from the front). glTF has no
//! environment: [`SceneFile::with_environment`] (`render --environment R,G,B`) adds a uniform
//! one ([`Scene::environment`]) and [`SceneFile::with_environment_map`] (`render
//! --environment FILE.exr|FILE.hdr`) an equirectangular map ([`Scene::environment_map`],
//! [`EnvironmentMap`]), seen by every ray that leaves the scene; light sampling picks it with
//! [`Scene::environment_pmf`] and samples a uniform one with cosine-distributed directions, a
//! map in proportion to its luminance. A scene's extras may name either
//! (`"extras": {"mcg": {"environment": [r, g, b]}}` or `… "environment": "sky.exr"`, turned
//! about +Y by `… "environment_rotation": degrees`), and
//! the openings through which it lights an interior (`… "portals": [[cx, cy, cz, ux, uy, uz,
//! vx, vy, vz], …]`, a corner and two edges each, [`Portal`]): light samples of a uniform
//! environment then aim at uniform points of them ([`Scene::portals`];
//! [`SceneFile::without_portals`], `render --no-portals`, ignores them).

use std::fmt;
use std::path::{Path, PathBuf};

use std::sync::Arc;

use glam::{Mat4, Quat, Vec2, Vec3};
use gltf::animation::{Interpolation, Property, util::ReadOutputs};
use mcg_markov_guide::mcpg::luminance;

use bytemuck::{Pod, Zeroable};

use super::bvh::{Bvh, Hit, Triangle};
use super::environment::{EnvironmentMap, Portal};
use super::material::{Material, NO_TEXTURE};

/// The glTF extensions the loader reads; [`Scene::warnings`] names any other a file uses.
pub const READ_EXTENSIONS: [&str; 3] = [
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_texture_transform",
];

/// Frames per second of the renderer's clock: frame `f` shows the scene at `f / FRAME_RATE`
/// seconds of its animations.
pub const FRAME_RATE: f32 = 24.0;

/// The animation time of frame `frame`, in seconds ([`FRAME_RATE`]).
#[must_use]
pub fn frame_time(frame: u32) -> f32 {
    frame as f32 / FRAME_RATE
}

/// What is wrong with a scene file. Every variant names the file.
#[derive(Debug)]
pub enum SceneError {
    /// The file could not be read or is not valid glTF 2.0 (the reason is the parser's).
    Unreadable {
        /// The file.
        path: PathBuf,
        /// The reader's or parser's message.
        reason: String,
    },
    /// The environment map given for the file, or named by its extras, could not be read or
    /// is not a map ([`EnvironmentMap::open`]).
    EnvironmentMap {
        /// The scene file.
        path: PathBuf,
        /// What is wrong, naming the map's file.
        reason: String,
    },
    /// The file holds no scene.
    NoScene {
        /// The file.
        path: PathBuf,
    },
    /// The default scene has no node with a perspective camera.
    NoCamera {
        /// The file.
        path: PathBuf,
    },
    /// The default scene has no triangle.
    NoTriangles {
        /// The file.
        path: PathBuf,
    },
    /// No triangle emits light (no material with a positive emissive factor, no point light).
    NoEmitters {
        /// The file.
        path: PathBuf,
        /// The file's spot and directional lights in the scene (`KHR_lights_punctual`), which
        /// the renderer does not render.
        unrendered_lights: usize,
    },
    /// A mesh primitive has no POSITION attribute.
    MissingPositions {
        /// The file.
        path: PathBuf,
        /// Index of the mesh.
        mesh: usize,
    },
    /// A vertex position, transform or material value is NaN or infinite, or a camera's
    /// `yfov` is not in (0, π).
    NonFinite {
        /// The file.
        path: PathBuf,
        /// What holds the value.
        what: String,
    },
    /// The BVH is deeper than the tracer's traversal stack ([`super::bvh::STACK_SIZE`]).
    BvhTooDeep {
        /// The file.
        path: PathBuf,
        /// The depth of the tree.
        depth: usize,
    },
    /// [`SceneFile::with_subdivision`] would make more than [`MAX_TRIANGLES`] triangles.
    TooManyTriangles {
        /// The file.
        path: PathBuf,
        /// The triangles the subdivision would make.
        triangles: u64,
    },
    /// A texture is not an 8-bit image, or cannot be decoded.
    UnsupportedTexture {
        /// The file.
        path: PathBuf,
        /// Index of the image.
        image: usize,
        /// What is wrong.
        reason: String,
    },
    /// A played animation channel's keyframes are unreadable, differ in count from its times,
    /// or do not match its property (channels the renderer does not play are skipped with a
    /// warning).
    UnsupportedAnimation {
        /// The file.
        path: PathBuf,
        /// Index of the animation.
        animation: usize,
        /// What is not supported.
        reason: String,
    },
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Unreadable { path, reason } => {
                write!(
                    f,
                    "{}: not a readable glTF 2.0 file: {reason}",
                    path.display()
                )
            }
            Self::EnvironmentMap { path, reason } => {
                write!(f, "{}: its environment map: {reason}", path.display())
            }
            Self::NoScene { path } => write!(f, "{}: the file has no scene", path.display()),
            Self::NoCamera { path } => write!(
                f,
                "{}: the default scene has no perspective camera (the renderer looks through \
                 the first one; --auto-camera places one)",
                path.display()
            ),
            Self::NoTriangles { path } => {
                write!(f, "{}: the default scene has no triangles", path.display())
            }
            Self::NoEmitters {
                path,
                unrendered_lights,
            } => write!(
                f,
                "{}: no emitters — no material has a positive emissiveFactor and no point \
                 light is there{}, so the image would be black (--environment R,G,B lights it \
                 from outside)",
                path.display(),
                if *unrendered_lights > 0 {
                    format!(
                        " (its {unrendered_lights} spot or directional light{} not rendered)",
                        if *unrendered_lights > 1 {
                            "s are"
                        } else {
                            " is"
                        }
                    )
                } else {
                    String::new()
                }
            ),
            Self::MissingPositions { path, mesh } => write!(
                f,
                "{}: mesh {mesh} has a primitive without POSITION",
                path.display()
            ),
            Self::NonFinite { path, what } => {
                write!(
                    f,
                    "{}: {what} is not finite or out of range",
                    path.display()
                )
            }
            Self::TooManyTriangles { path, triangles } => write!(
                f,
                "{}: subdivided, it would have {triangles} triangles; at most {MAX_TRIANGLES}",
                path.display()
            ),
            Self::BvhTooDeep { path, depth } => write!(
                f,
                "{}: the BVH over its triangles is {depth} levels deep; the tracer walks at \
                 most {}",
                path.display(),
                super::bvh::STACK_SIZE
            ),
            Self::UnsupportedTexture {
                path,
                image,
                reason,
            } => write!(
                f,
                "{}: image {image} cannot be used as a texture: {reason}",
                path.display()
            ),
            Self::UnsupportedAnimation {
                path,
                animation,
                reason,
            } => write!(
                f,
                "{}: animation {animation} is not supported: {reason}",
                path.display()
            ),
        }
    }
}

impl std::error::Error for SceneError {}

/// A perspective pinhole camera in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// The eye position.
    pub position: Vec3,
    /// Unit vector to the image's right.
    pub right: Vec3,
    /// Unit vector to the image's top.
    pub up: Vec3,
    /// Unit viewing direction (the camera's local −Z).
    pub forward: Vec3,
    /// Vertical field of view in radians.
    pub yfov: f32,
}

impl Camera {
    /// A camera at `eye` looking at `target` (a different point) with +Y up, or +Z where it
    /// looks straight up or down, and vertical field of view `yfov` (radians).
    #[must_use]
    pub fn looking_at(eye: Vec3, target: Vec3, yfov: f32) -> Self {
        let forward = (target - eye).normalize();
        let right = forward.cross(Vec3::Y);
        let right = if right.length_squared() > 1e-12 {
            right.normalize()
        } else {
            forward.cross(Vec3::Z).normalize()
        };
        Self {
            position: eye,
            right,
            up: right.cross(forward),
            forward,
            yfov,
        }
    }

    /// The unit direction through the image point `(x, y)` in pixels (fractional, origin at
    /// the top-left corner, y down) of a `width × height` image.
    #[must_use]
    pub fn direction(&self, x: f32, y: f32, width: u32, height: u32) -> Vec3 {
        let tan_y = (0.5 * self.yfov).tan();
        let tan_x = tan_y * width as f32 / height as f32;
        let sx = (2.0 * x / width as f32 - 1.0) * tan_x;
        let sy = (1.0 - 2.0 * y / height as f32) * tan_y;
        (self.forward + sx * self.right + sy * self.up).normalize()
    }
}

/// The radius of the sphere a point light becomes ([`SceneFile::build`]), as a fraction of
/// the diagonal of the scene's bounding box: 2 cm in a 10 m scene. Small enough that it lights
/// the scene as the point would, large enough that rays sampled from a material or a guide
/// hit it now and then — rarely: `nee` samples it directly, while `bsdf` and a young `mcpg`
/// guide find it by chance and show fireflies for many frames (easy-gltf's `head.glb`, three
/// point lights, 96², 8 frames of 8 spp: `nee` a clean image, `mcpg` sparse bright dots).
pub const POINT_LIGHT_RADIUS: f32 = 0.002;

/// The 20 faces of a regular icosahedron of circumradius `radius` about the origin, each
/// counter-clockwise seen from outside (its front face out, glTF's winding).
fn icosahedron(radius: f32) -> Vec<[Vec3; 3]> {
    let phi = 0.5 * (1.0 + 5.0f32.sqrt());
    let mut v = Vec::with_capacity(12);
    for (a, b) in [(1.0, phi), (-1.0, phi), (1.0, -phi), (-1.0, -phi)] {
        v.push(Vec3::new(0.0, a, b));
        v.push(Vec3::new(a, b, 0.0));
        v.push(Vec3::new(b, 0.0, a));
    }
    let scale = radius / Vec3::new(0.0, 1.0, phi).length();
    let edge = 2.0;
    let mut faces = Vec::with_capacity(20);
    for i in 0..12 {
        for j in i + 1..12 {
            for k in j + 1..12 {
                let (a, b, c) = (v[i], v[j], v[k]);
                let close = |p: Vec3, q: Vec3| ((p - q).length() - edge).abs() < 1e-3;
                if close(a, b) && close(b, c) && close(a, c) {
                    let (b, c) = if (b - a).cross(c - a).dot(a + b + c) > 0.0 {
                        (b, c)
                    } else {
                        (c, b)
                    };
                    faces.push([a * scale, b * scale, c * scale]);
                }
            }
        }
    }
    faces
}

/// `gltf::Gltf::open` of `path`, a panic inside the parser turned into
/// [`SceneError::Unreadable`]: gltf 1.4's validation indexes the accessors a primitive names
/// before checking that they exist (`POSITION` naming a missing accessor panics in
/// `gltf_json::mesh`), and a bad file must never take the process down. The panic's own
/// message is kept off the terminal while the parser runs (the process-wide hook is swapped
/// for that time; files are opened on the main thread, before any render starts).
fn parse(path: &Path) -> Result<gltf::Result<gltf::Gltf>, SceneError> {
    let previous = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let parsed = std::panic::catch_unwind(|| gltf::Gltf::open(path));
    std::panic::set_hook(previous);
    parsed.map_err(|payload| {
        let message = payload
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| payload.downcast_ref::<&str>().copied())
            .unwrap_or("no message");
        SceneError::Unreadable {
            path: path.to_path_buf(),
            reason: format!(
                "the glTF parser gave up on it ({message}); an index in the file likely names \
                 something that does not exist"
            ),
        }
    })
}

/// A glTF file in memory: the document and its buffers, ready to be built into a [`Scene`] at
/// any animation time.
pub struct SceneFile {
    path: PathBuf,
    document: gltf::Document,
    buffers: Vec<gltf::buffer::Data>,
    /// Every image a material's texture reads (each once, in the order of first use), packed
    /// as [`Scene::texels`] are: its index in the document, width, height and texels.
    images: Vec<(usize, u32, u32, Vec<u32>)>,
    /// The textures the materials read ([`Scene::textures`]).
    textures: Vec<TextureUse>,
    /// [`Scene::environment`] of the scenes it builds.
    environment: Vec3,
    /// [`Scene::environment_map`] of the scenes it builds.
    environment_map: Option<Arc<EnvironmentMap>>,
    /// [`Scene::portals`] of the scenes it builds (the extras' `mcg.portals`).
    portals: Vec<Portal>,
    /// Whether a scene without a camera gets [`auto_camera`]'s.
    auto_camera: bool,
    /// How often each non-emitting triangle is split in four ([`SceneFile::with_subdivision`]).
    subdivision: u32,
    /// A camera that replaces the file's ([`SceneFile::with_camera`]): eye, target and the
    /// vertical field of view (radians) if given.
    camera: Option<(Vec3, Vec3, Option<f32>)>,
}

/// The most triangles a scene may have after [`SceneFile::with_subdivision`] (2²⁴: 1.2 GB of
/// triangles and attributes).
pub const MAX_TRIANGLES: u32 = 1 << 24;

/// Whether a triangle of `material` emits (and so is never subdivided).
fn emits(material: &Material) -> bool {
    material.emission != [0.0; 3]
}

/// The triangles [`subdivide`] makes.
fn subdivided_count(triangles: &[Triangle], materials: &[Material], levels: u32) -> u64 {
    let split = 4u64.saturating_pow(levels);
    triangles
        .iter()
        .map(|t| {
            if emits(&materials[t.material as usize]) {
                1
            } else {
                split
            }
        })
        .fold(0, u64::saturating_add)
}

/// [`SceneFile::with_subdivision`]: every non-emitting triangle split into four at its edges'
/// midpoints, `levels` times. A child keeps its parent's winding (so its front face, and
/// glTF's counter-clockwise rule) and material; its corners' positions are the midpoints of
/// its parent's (`(a + b) / 2`, the same for both triangles that share an edge), and its
/// attributes those of its parent at its corners' barycentrics.
fn subdivide(
    triangles: &[Triangle],
    attributes: &[TriangleAttributes],
    materials: &[Material],
    levels: u32,
) -> (Vec<Triangle>, Vec<TriangleAttributes>) {
    /// A corner: its position and its barycentrics (b1, b2) in the original triangle.
    type Corner = (Vec3, [f32; 2]);
    fn split(corners: [Corner; 3], levels: u32, emit: &mut impl FnMut([Corner; 3])) {
        if levels == 0 {
            emit(corners);
            return;
        }
        let mid = |(p, a): Corner, (q, b): Corner| {
            ((p + q) * 0.5, [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])])
        };
        let [c0, c1, c2] = corners;
        let (m01, m12, m20) = (mid(c0, c1), mid(c1, c2), mid(c2, c0));
        for child in [
            [c0, m01, m20],
            [m01, c1, m12],
            [m20, m12, c2],
            [m01, m12, m20],
        ] {
            split(child, levels - 1, emit);
        }
    }
    let mut out = Vec::new();
    let mut out_attributes = Vec::new();
    for (t, a) in triangles.iter().zip(attributes) {
        if emits(&materials[t.material as usize]) {
            out.push(*t);
            out_attributes.push(*a);
            continue;
        }
        let v0 = Vec3::from(t.v0);
        let corners = [
            (v0, [0.0, 0.0]),
            (v0 + Vec3::from(t.e1), [1.0, 0.0]),
            (v0 + Vec3::from(t.e2), [0.0, 1.0]),
        ];
        split(corners, levels, &mut |[(p0, b0), (p1, b1), (p2, b2)]| {
            let mut child = Triangle::new(p0, p1, p2, t.material);
            child.emitter_pmf = t.emitter_pmf;
            out.push(child);
            out_attributes.push(a.at_corners([b0, b1, b2]));
        });
    }
    (out, out_attributes)
}

/// What a material's texture slot reads: an image (its index in the document) through a map
/// of texture coordinates ([`TextureInfo::map`]) and wrap modes ([`TextureInfo::wrap`]).
#[derive(Clone, Copy, Debug, PartialEq)]
struct TextureUse {
    image: usize,
    map: [[f32; 4]; 2],
    wrap: u32,
}

/// A texture as materials read it: where its texels are in [`Scene::texels`] and the map of
/// texture coordinates in front of the lookup (`KHR_texture_transform`); 48 bytes, a
/// `vec4<u32>` and two `vec4<f32>` in WGSL.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct TextureInfo {
    /// Index of the first texel (row-major from the top-left).
    pub offset: u32,
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// How coordinates outside [0, 1] wrap (the glTF sampler's `wrapS` and `wrapT`):
    /// `s | t << 16`, each [`WRAP_REPEAT`], [`WRAP_CLAMP`] or [`WRAP_MIRROR`].
    pub wrap: u32,
    /// The rows `(a, b, c, 0)` and `(d, e, f, 0)` of the affine map
    /// `(u, v) ↦ (a·u + b·v + c, d·u + e·v + f)` applied to a hit's texture coordinates
    /// ([`TextureInfo::transform`]); [`TextureInfo::IDENTITY`] without the extension.
    pub map: [[f32; 4]; 2],
}

impl TextureInfo {
    /// The map of a texture without `KHR_texture_transform`.
    pub const IDENTITY: [[f32; 4]; 2] = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]];

    /// `KHR_texture_transform`'s map of texture coordinates, `translation · rotation · scale`
    /// (the extension's specification, in column-major GLSL): rotation by `rotation` radians
    /// counter-clockwise, `(u, v) ↦ (cos·s_u·u − sin·s_v·v + o_u, sin·s_u·u + cos·s_v·v + o_v)`.
    #[must_use]
    pub fn transform(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> [[f32; 4]; 2] {
        let (sin, cos) = rotation.sin_cos();
        [
            [cos * scale[0], -sin * scale[1], offset[0], 0.0],
            [sin * scale[0], cos * scale[1], offset[1], 0.0],
        ]
    }

    /// `[u, v]` through [`TextureInfo::map`].
    #[must_use]
    pub fn mapped(&self, [u, v]: [f32; 2]) -> [f32; 2] {
        self.map.map(|[a, b, c, _]| a * u + b * v + c)
    }
}

/// [`Scene::environment_pmf`] of a scene with both an environment and emitting triangles.
pub const ENVIRONMENT_PICK: f32 = 0.5;

/// What light sampling picked ([`Scene::pick_light`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// The environment, with probability [`Scene::environment_pmf`].
    Environment,
    /// An emitting triangle (its index in the scene's tree, leaf order) and the probability
    /// of picking it ([`Triangle::emitter_pmf`]).
    Triangle(u32, f32),
}

/// The barycentric points (b1, b2) at which [`Scene::weigh_emitters_by_texture`] reads an
/// emitter's texture: the centroids of the ten upright triangles of its 4 × 4 subdivision.
pub const EMISSION_PROBES: [(f32, f32); 10] = {
    let mut points = [(0.0, 0.0); 10];
    let mut k = 0;
    let mut i = 0;
    while i < 4 {
        let mut j = 0;
        while i + j < 4 {
            points[k] = ((i as f32 + 1.0 / 3.0) / 4.0, (j as f32 + 1.0 / 3.0) / 4.0);
            k += 1;
            j += 1;
        }
        i += 1;
    }
    points
};

/// The least share of its factor's power an emitter with an emissive texture keeps in light
/// selection ([`Scene::weigh_emitters_by_texture`]).
pub const MIN_TEXTURE_POWER: f32 = 1.0 / 32.0;

/// [`TextureInfo::wrap`] of glTF's REPEAT (the default): the coordinate's fraction.
pub const WRAP_REPEAT: u32 = 0;
/// [`TextureInfo::wrap`] of glTF's CLAMP_TO_EDGE: the coordinate clamped to [0, 1].
pub const WRAP_CLAMP: u32 = 1;
/// [`TextureInfo::wrap`] of glTF's MIRRORED_REPEAT: every other period mirrored.
pub const WRAP_MIRROR: u32 = 2;

/// A texture coordinate `c` wrapped by `mode` ([`TextureInfo::wrap`]) to the texel index
/// below `size` (nearest texel).
#[must_use]
pub fn wrapped_texel(c: f32, mode: u32, size: u32) -> u32 {
    let f = match mode {
        WRAP_CLAMP => c.clamp(0.0, 1.0),
        WRAP_MIRROR => {
            let t = c - 2.0 * (0.5 * c).floor();
            if t > 1.0 { 2.0 - t } else { t }
        }
        _ => c - c.floor(),
    };
    ((f * size as f32) as u32).min(size - 1)
}

/// What a triangle's three vertices carry besides their positions: texture coordinates
/// (`TEXCOORD_0`) and colours with their alpha (`COLOR_0`); 48 bytes, three `vec2<f32>` and
/// three `vec2<u32>` in WGSL.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct TriangleAttributes {
    /// `(u, v)` of `v0`, `v1` and `v2`; zero without them.
    pub uv: [[f32; 2]; 3],
    /// The linear RGBA of `v0`, `v1` and `v2` as 16-bit unorms, `[r | g << 16, b | a << 16]`
    /// (WGSL `unpack2x16unorm`); [`TriangleAttributes::WHITE`] without them.
    pub color: [[u32; 2]; 3],
}

impl TriangleAttributes {
    /// [`TriangleAttributes::color`] of a vertex without a colour: opaque white.
    pub const WHITE: [u32; 2] = [u32::MAX; 2];

    /// Linear RGBA in [0, 1] as [`TriangleAttributes::color`] stores it.
    #[must_use]
    pub fn pack_color([r, g, b, a]: [f32; 4]) -> [u32; 2] {
        let unorm = |c: f32| (c.clamp(0.0, 1.0) * 65535.0).round() as u32;
        [unorm(r) | unorm(g) << 16, unorm(b) | unorm(a) << 16]
    }

    /// The texture coordinates at barycentrics (`b1`, `b2`).
    #[must_use]
    pub fn uv_at(&self, b1: f32, b2: f32) -> [f32; 2] {
        let b0 = 1.0 - b1 - b2;
        [0, 1].map(|k| b0 * self.uv[0][k] + b1 * self.uv[1][k] + b2 * self.uv[2][k])
    }

    /// The colour at barycentrics (`b1`, `b2`): `c₀ + b1·(c₁ − c₀) + b2·(c₂ − c₀)`, which is
    /// exactly `c₀` where the three are equal (white stays 1).
    #[must_use]
    pub fn color_at(&self, b1: f32, b2: f32) -> Vec3 {
        let unpack = |[rg, b]: [u32; 2]| {
            let unorm = |v: u32| (v & 0xffff) as f32 / 65535.0;
            Vec3::new(unorm(rg), unorm(rg >> 16), unorm(b))
        };
        let [c0, c1, c2] = self.color.map(unpack);
        c0 + b1 * (c1 - c0) + b2 * (c2 - c0)
    }

    /// The attributes of the triangle whose corners lie at barycentrics `corners` (each
    /// `(b1, b2)`) of this one: texture coordinates and colours interpolated there (colours
    /// rounded to 16-bit unorms again).
    #[must_use]
    pub fn at_corners(&self, corners: [[f32; 2]; 3]) -> Self {
        Self {
            uv: corners.map(|[b1, b2]| self.uv_at(b1, b2)),
            color: corners.map(|[b1, b2]| {
                let c = self.color_at(b1, b2);
                Self::pack_color([c.x, c.y, c.z, self.alpha_at(b1, b2)])
            }),
        }
    }

    /// The vertex colours' alpha at barycentrics (`b1`, `b2`), interpolated as
    /// [`color_at`](Self::color_at) (exactly 1 where the three are opaque).
    #[must_use]
    pub fn alpha_at(&self, b1: f32, b2: f32) -> f32 {
        let [a0, a1, a2] = self.color.map(|[_, ba]| (ba >> 16) as f32 / 65535.0);
        a0 + b1 * (a1 - a0) + b2 * (a2 - a0)
    }
}

impl Default for TriangleAttributes {
    /// No texture coordinates, white.
    fn default() -> Self {
        Self {
            uv: [[0.0; 2]; 3],
            color: [Self::WHITE; 3],
        }
    }
}

impl fmt::Debug for SceneFile {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SceneFile")
            .field("path", &self.path)
            .finish_non_exhaustive()
    }
}

/// A scene ready to trace: the camera, the BVH over world-space triangles, materials, and the
/// emitter table of light sampling.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The camera.
    pub camera: Camera,
    /// The BVH and the triangles in its leaf order.
    pub bvh: Bvh,
    /// Materials, indexed by [`Triangle::material`]; index 0 is glTF's default material.
    pub materials: Vec<Material>,
    /// Indices (into `bvh.triangles`) of the front-emitting triangles.
    pub emitters: Vec<u32>,
    /// The front-emitting triangles alone, in a BVH of their own (their [`Triangle::material`]
    /// indexes [`Scene::materials`]): a ray that only gathers emission (`mcpg`'s second
    /// direction) finds the nearest emitter facing it here and then tests whether anything
    /// blocks the way, instead of walking the whole scene for its first hit.
    pub emitter_bvh: Bvh,
    /// Inclusive cumulative distribution over `emitters`, proportional to each triangle's
    /// emitted power `area × luminance(L_e)`; the last entry is 1.
    pub emitter_cdf: Vec<f32>,
    /// The radiance that arrives from outside the scene along every direction (a uniform
    /// environment, as a sky seen through the scene's openings), linear RGB: what a ray that
    /// leaves the scene sees. Zero (the default) for none. With an
    /// [`Scene::environment_map`], the factor its radiance is multiplied by
    /// ([`Scene::environment_radiance`]).
    pub environment: Vec3,
    /// An environment map ([`EnvironmentMap`]) that gives the environment's radiance per
    /// direction, times [`Scene::environment`]; light sampling then draws directions in
    /// proportion to its luminance instead of cosine-distributed ones.
    pub environment_map: Option<Arc<EnvironmentMap>>,
    /// The openings through which a uniform environment lights the scene ([`Portal`]; empty
    /// for none): its light samples aim at them ([`Scene::sample_environment`]; an
    /// [`Scene::environment_map`]'s follow the map, since aiming uniformly at a window misses
    /// the sun that the map's own samples find). The scene's extras name them
    /// (`mcg.portals`); [`Scene::set_portals`] sets their pmfs.
    pub portals: Vec<Portal>,
    /// The probability that light sampling picks the environment rather than a triangle
    /// ([`Scene::pick_light`]): 0 without an environment, 1 without emitting triangles, else
    /// [`ENVIRONMENT_PICK`]. The triangles' [`Triangle::emitter_pmf`] sum to 1 − this.
    pub environment_pmf: f32,
    /// Texture coordinates and vertex colours per triangle, in the order of `bvh.triangles`
    /// (empty when no material has a texture and no primitive has colours).
    pub attributes: Vec<TriangleAttributes>,
    /// The textures, indexed by [`Material::base_color_texture`] and its siblings.
    pub textures: Vec<TextureInfo>,
    /// The texels of all textures, 8-bit RGBA packed red in the low byte (WGSL
    /// `unpack4x8unorm`), as the file stores them: [`Scene::material_at`] decodes each as its
    /// use asks (glTF 2.0, "Materials": base-colour and emissive textures are sRGB-encoded,
    /// metallic-roughness textures linear), so one image serves both kinds of use.
    pub texels: Vec<u32>,
    /// Things the loader ignored, one sentence each.
    pub warnings: Vec<String>,
}

impl SceneFile {
    /// Reads a `.gltf` (with `.bin` files or embedded base64 buffers) or a `.glb`, with the
    /// environment its scene's extras name (`"extras": {"mcg": {"environment": [r, g, b]}}`,
    /// as the built-in `sky_room`, or an environment map's file relative to the glTF file,
    /// `"environment": "sky.exr"`; [`SceneFile::with_environment`] and
    /// [`SceneFile::with_environment_map`] replace it).
    ///
    /// # Errors
    /// [`SceneError::Unreadable`] when the file is missing or not glTF 2.0,
    /// [`SceneError::NoScene`] when it holds no scene, [`SceneError::NonFinite`] for an
    /// environment in the extras that is neither three finite non-negative numbers nor a
    /// string, [`SceneError::EnvironmentMap`] for an environment map that cannot be read.
    pub fn open(path: impl AsRef<Path>) -> Result<Self, SceneError> {
        let path = path.as_ref().to_path_buf();
        let unreadable = |e: gltf::Error| SceneError::Unreadable {
            path: path.clone(),
            reason: e.to_string(),
        };
        let gltf::Gltf { document, blob } = parse(&path)?.map_err(unreadable)?;
        let buffers = gltf::import_buffers(&document, path.parent(), blob).map_err(unreadable)?;
        if document.scenes().len() == 0 {
            return Err(SceneError::NoScene { path });
        }
        let extras = extras_environment(&document).ok_or_else(|| SceneError::NonFinite {
            path: path.clone(),
            what: "the environment in the scene's extras (mcg.environment: [r, g, b] or \
                   \"map.exr\")"
                .to_owned(),
        })?;
        let portals = extras_portals(&document).ok_or_else(|| SceneError::NonFinite {
            path: path.clone(),
            what: "the portals in the scene's extras (mcg.portals: [[corner, edge, edge] as 9 \
                   numbers, …], each of positive area)"
                .to_owned(),
        })?;
        let (environment, environment_map) = match extras {
            Err(radiance) => (radiance, None),
            Ok(file) => {
                let degrees =
                    extras_number(&document, "environment_rotation").ok_or_else(|| {
                        SceneError::NonFinite {
                            path: path.clone(),
                            what: "the environment's rotation in the scene's extras \
                               (mcg.environment_rotation, degrees)"
                                .to_owned(),
                        }
                    })?;
                let map = path.parent().unwrap_or(Path::new("")).join(file);
                (Vec3::ONE, Some(open_environment_map(&path, &map, degrees)?))
            }
        };
        let textures = used_textures(&document);
        let mut images: Vec<(usize, u32, u32, Vec<u32>)> = Vec::new();
        if !textures.is_empty() {
            let decoded =
                gltf::import_images(&document, path.parent(), &buffers).map_err(unreadable)?;
            for &TextureUse { image, .. } in &textures {
                if images.iter().any(|i| i.0 == image) {
                    continue;
                }
                let data = &decoded[image];
                let texels = rgba8(data).map_err(|reason| SceneError::UnsupportedTexture {
                    path: path.clone(),
                    image,
                    reason,
                })?;
                images.push((image, data.width, data.height, texels));
            }
        }
        Ok(Self {
            path,
            document,
            buffers,
            images,
            textures,
            environment,
            environment_map,
            portals,
            auto_camera: false,
            subdivision: 0,
            camera: None,
        })
    }

    /// The file with a camera placed for scenes that have none ([`SceneFile::build`] warns
    /// when it does): looking down −Z (glTF's forward) at the centre of the triangles'
    /// bounding box from far enough that its bounding sphere fills the 45° vertical field of
    /// view, +Y up. A camera in the file still wins.
    #[must_use]
    pub fn with_auto_camera(mut self) -> Self {
        self.auto_camera = true;
        self
    }

    /// The file lit by a uniform environment of radiance `radiance` too ([`Scene::environment`];
    /// glTF has none): the scenes it builds need no emitting triangle then. Non-finite or
    /// negative channels are an error.
    ///
    /// # Errors
    /// [`SceneError::NonFinite`] for a radiance that is not finite and non-negative.
    pub fn with_environment(mut self, radiance: Vec3) -> Result<Self, SceneError> {
        if !(radiance.is_finite() && radiance.min_element() >= 0.0) {
            return Err(SceneError::NonFinite {
                path: self.path.clone(),
                what: format!("the environment radiance {radiance}"),
            });
        }
        self.environment = radiance;
        self.environment_map = None;
        Ok(self)
    }

    /// The file lit by the environment map in the file `map` too (an equirectangular OpenEXR
    /// or Radiance image, [`EnvironmentMap::open`]; [`Scene::environment_map`]), replacing any
    /// environment the file names: the scenes it builds need no emitting triangle then.
    ///
    /// # Errors
    /// [`SceneError::EnvironmentMap`] when the map cannot be read, naming it and what is
    /// wrong.
    pub fn with_environment_map(mut self, map: &Path) -> Result<Self, SceneError> {
        self.environment_map = Some(open_environment_map(&self.path, map, 0.0)?);
        self.environment = Vec3::ONE;
        Ok(self)
    }

    /// The file seen by a camera at `eye` looking at `target` with +Y up (+Z where it looks
    /// straight up or down), replacing the file's camera (`render --camera`): the vertical
    /// field of view is `yfov_degrees`, else the file camera's, else 45°.
    ///
    /// # Errors
    /// [`SceneError::NonFinite`] for an eye or target that is not finite, the two at the same
    /// point, or a field of view outside (0°, 180°).
    pub fn with_camera(
        mut self,
        eye: Vec3,
        target: Vec3,
        yfov_degrees: Option<f32>,
    ) -> Result<Self, SceneError> {
        let yfov = yfov_degrees.map(f32::to_radians);
        let what = if !(eye.is_finite() && target.is_finite()) {
            Some(format!("the camera at {eye} looking at {target}"))
        } else if !((target - eye).length() > 0.0) {
            Some(format!(
                "the camera's direction (its eye and target are both {eye})"
            ))
        } else if !yfov.is_none_or(|f| f > 0.0 && f < core::f32::consts::PI) {
            yfov_degrees.map(|d| format!("the camera's field of view {d}° (0° to 180°)"))
        } else {
            None
        };
        if let Some(what) = what {
            return Err(SceneError::NonFinite {
                path: self.path.clone(),
                what,
            });
        }
        self.camera = Some((eye, target, yfov));
        Ok(self)
    }

    /// The file with its environment map turned by `degrees` about +Y
    /// ([`EnvironmentMap::with_rotation`]; `render --environment-rotation`), replacing any
    /// rotation its extras name (`mcg.environment_rotation`, degrees); no effect on a uniform
    /// environment.
    ///
    /// # Errors
    /// [`SceneError::NonFinite`] for an angle that is not finite.
    pub fn with_environment_rotation(mut self, degrees: f32) -> Result<Self, SceneError> {
        if !degrees.is_finite() {
            return Err(SceneError::NonFinite {
                path: self.path.clone(),
                what: format!("the environment's rotation {degrees}°"),
            });
        }
        if let Some(map) = &self.environment_map {
            let turned = (**map).clone().with_rotation(degrees.to_radians());
            self.environment_map = Some(Arc::new(turned));
        }
        Ok(self)
    }

    /// The file with every triangle that emits nothing split into four at its edges'
    /// midpoints, `levels` times over (4^`levels` triangles each, `render --subdivide`): the
    /// same surfaces, textures and vertex colours (interpolated to the new corners) in more
    /// triangles, so that a ray costs what it costs in a larger BVH while the image stays the
    /// same in expectation. Emitting triangles stay as they are, so light sampling and the
    /// emitters' own structures do not change. For measuring how a method's frame cost
    /// compares with the rays' as the scene grows; [`SceneFile::build`] refuses more than
    /// [`MAX_TRIANGLES`].
    #[must_use]
    pub fn with_subdivision(mut self, levels: u32) -> Self {
        self.subdivision = levels;
        self
    }

    /// The file without the portals its extras name: light samples of the environment then
    /// ignore the openings (`render --no-portals`).
    #[must_use]
    pub fn without_portals(mut self) -> Self {
        self.portals.clear();
        self
    }

    /// The file's path.
    #[must_use]
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Whether the file has animations (then each frame needs its own [`SceneFile::build`]).
    #[must_use]
    pub fn is_animated(&self) -> bool {
        self.document
            .animations()
            .flat_map(|a| a.channels().collect::<Vec<_>>())
            .any(|c| self.unplayed_channel(&c).is_none())
    }

    /// Why the renderer does not play `channel` (its node then keeps its rest transform, and
    /// [`Scene::warnings`] says so), or `None` when it does: CUBICSPLINE interpolation,
    /// morph-target weights, and a node whose transform is a matrix (glTF 2.0 animates only
    /// nodes given as translation, rotation and scale).
    fn unplayed_channel(&self, channel: &gltf::animation::Channel) -> Option<String> {
        let target = channel.target();
        if target.property() == Property::MorphTargetWeights {
            return Some("morph-target weights".to_owned());
        }
        if channel.sampler().interpolation() == Interpolation::CubicSpline {
            return Some("CUBICSPLINE interpolation".to_owned());
        }
        if matches!(
            target.node().transform(),
            gltf::scene::Transform::Matrix { .. }
        ) {
            return Some(format!(
                "node {} has a matrix transform",
                target.node().index()
            ));
        }
        None
    }

    /// Builds the scene at animation time `time` (seconds).
    ///
    /// # Errors
    /// [`SceneError`] when the default scene has no camera, no triangles or no emitters, or
    /// uses what the renderer does not support (see the module docs).
    pub fn build(&self, time: f32) -> Result<Scene, SceneError> {
        let path = &self.path;
        let scene = self
            .document
            .default_scene()
            .or_else(|| self.document.scenes().next())
            .ok_or_else(|| SceneError::NoScene { path: path.clone() })?;
        let locals = self.local_transforms(time)?;

        let mut warnings = Vec::new();
        let mut materials = self.materials(&mut warnings)?;
        self.unread_features(&mut warnings);

        let mut triangles = Vec::new();
        let mut attributes = Vec::new();
        let mut camera = None;
        let mut lights = Vec::new();
        let mut stack: Vec<(gltf::Node, Mat4)> =
            scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
        stack.reverse();
        // glTF 2.0 ("Nodes and Hierarchy"): the nodes form disjoint strict trees, so a scene
        // reaches each node once; a cycle would make this walk endless.
        let mut reached = vec![false; self.document.nodes().len()];
        while let Some((node, parent)) = stack.pop() {
            if std::mem::replace(&mut reached[node.index()], true) {
                return Err(SceneError::Unreadable {
                    path: path.clone(),
                    reason: format!(
                        "node {} is reached twice from the scene (a cycle in the node \
                         hierarchy, a node with two parents, or listed twice), which glTF 2.0 \
                         forbids",
                        node.index()
                    ),
                });
            }
            let world = parent * locals[node.index()];
            if !world.is_finite() {
                return Err(SceneError::NonFinite {
                    path: path.clone(),
                    what: format!("the transform of node {}", node.index()),
                });
            }
            if camera.is_none() {
                camera = self.node_camera(&node, world)?;
            }
            if let Some(light) = node.light() {
                lights.push((light, world.w_axis.truncate()));
            }
            if let Some(mesh) = node.mesh() {
                self.push_mesh(&mesh, world, &materials, &mut triangles, &mut attributes)?;
            }
            for child in node.children().collect::<Vec<_>>().into_iter().rev() {
                stack.push((child, world));
            }
        }
        if triangles.is_empty() {
            return Err(SceneError::NoTriangles { path: path.clone() });
        }
        let unrendered_lights = self.push_point_lights(
            &lights,
            &mut materials,
            &mut triangles,
            &mut attributes,
            &mut warnings,
        )?;
        if self.subdivision > 0 {
            let made = subdivided_count(&triangles, &materials, self.subdivision);
            if made > MAX_TRIANGLES as u64 {
                return Err(SceneError::TooManyTriangles {
                    path: path.clone(),
                    triangles: made,
                });
            }
            (triangles, attributes) =
                subdivide(&triangles, &attributes, &materials, self.subdivision);
        }
        let camera = match (camera, self.camera) {
            (file, Some((eye, target, yfov))) => {
                let yfov = yfov
                    .or(file.map(|c| c.yfov))
                    .unwrap_or(core::f32::consts::FRAC_PI_4);
                Camera::looking_at(eye, target, yfov)
            }
            (Some(camera), None) => camera,
            (None, None) if self.auto_camera => {
                warnings.push(
                    "the file has no camera: one looks down -Z at the whole scene".to_owned(),
                );
                auto_camera(&triangles)
            }
            (None, None) => return Err(SceneError::NoCamera { path: path.clone() }),
        };
        let mut scene = Scene::new_lit(camera, &triangles, materials, warnings, self.environment)
            .ok_or_else(|| SceneError::NoEmitters {
            path: path.clone(),
            unrendered_lights,
        })?;
        if let Some(map) = &self.environment_map {
            scene.environment_map = Some(Arc::clone(map));
        }
        if scene.environment != Vec3::ZERO && !self.portals.is_empty() {
            scene.set_portals(self.portals.clone());
        }
        let depth = scene.bvh.depth();
        if depth > super::bvh::STACK_SIZE {
            return Err(SceneError::BvhTooDeep {
                path: path.clone(),
                depth,
            });
        }
        self.attach_attributes(&mut scene, &attributes);
        scene.weigh_emitters_by_texture();
        Ok(scene)
    }

    /// KHR_lights_punctual's point lights as small emitting spheres (icosahedra of radius
    /// [`POINT_LIGHT_RADIUS`] × the diagonal of the triangles' bounding box, centred at the
    /// light node's world position), so that every method, guides included, can hit them: a
    /// point has no area to hit, and a guide without light information would never find it.
    /// Each gets a material of its own whose front-face radiance gives the icosahedron the
    /// light's power Φ = 4π·I (I = `intensity` × `color`, in candela, lm/sr): a Lambertian
    /// emitter of area A and radiance L emits Φ = π·L·A, so L = 4·I / A — cd/m², glTF's unit
    /// of emission. Seen from afar it shines with I on average over directions (the mean
    /// projected area of a convex body is A/4); its `range` is not read (the falloff is the
    /// physical 1/d²). Spot and directional lights are not rendered; the warnings say so.
    ///
    /// Returns how many lights it did not render (spot and directional).
    ///
    /// # Errors
    /// [`SceneError::NonFinite`] for an intensity or colour that is not finite and ≥ 0.
    fn push_point_lights(
        &self,
        lights: &[(gltf::khr_lights_punctual::Light, Vec3)],
        materials: &mut Vec<Material>,
        triangles: &mut Vec<Triangle>,
        attributes: &mut Vec<TriangleAttributes>,
        warnings: &mut Vec<String>,
    ) -> Result<usize, SceneError> {
        use gltf::khr_lights_punctual::Kind;
        if lights.is_empty() {
            return Ok(0);
        }
        let (lo, hi) = bounds(triangles);
        let radius = POINT_LIGHT_RADIUS * (hi - lo).length();
        let faces = icosahedron(radius);
        let area: f32 = faces
            .iter()
            .map(|[a, b, c]| 0.5 * (*b - *a).cross(*c - *a).length())
            .sum();
        let mut skipped: Vec<String> = Vec::new();
        for (light, position) in lights {
            if !matches!(light.kind(), Kind::Point) {
                skipped.push(light.index().to_string());
                continue;
            }
            let intensity = Vec3::from(light.color()) * light.intensity();
            if !(intensity.is_finite() && intensity.min_element() >= 0.0) {
                return Err(SceneError::NonFinite {
                    path: self.path.clone(),
                    what: format!("the colour × intensity of light {}", light.index()),
                });
            }
            let material = materials.len() as u32;
            materials.push(Material {
                base_color: [0.0; 3],
                metallic: 0.0,
                emission: (4.0 * intensity / area).to_array(),
                roughness: 1.0,
                ..Material::default()
            });
            for [a, b, c] in &faces {
                triangles.push(Triangle::new(
                    *position + *a,
                    *position + *b,
                    *position + *c,
                    material,
                ));
                attributes.push(TriangleAttributes::default());
            }
        }
        if !skipped.is_empty() {
            warnings.push(format!(
                "light{} {}: spot and directional lights (KHR_lights_punctual) are not \
                 rendered, only point lights",
                if skipped.len() > 1 { "s" } else { "" },
                skipped.join(", ")
            ));
        }
        Ok(skipped.len())
    }

    /// The document's materials after the default one (index 0), checked finite; warns of
    /// textures on other texture coordinates than `TEXCOORD_0`.
    fn materials(&self, warnings: &mut Vec<String>) -> Result<Vec<Material>, SceneError> {
        let path = &self.path;
        let mut materials = vec![Material::default()];
        for m in self.document.materials() {
            let pbr = m.pbr_metallic_roughness();
            let [r, g, b, a] = pbr.base_color_factor();
            let strength = m.emissive_strength().unwrap_or(1.0);
            let emission = Vec3::from(m.emissive_factor()) * strength;
            let mut texture =
                |info: Option<gltf::texture::Info>, what: &str, factor: &str| match info {
                    None => Ok(NO_TEXTURE),
                    Some(info) => match texture_use(&info) {
                        Ok(used) => {
                            if used.map.iter().flatten().any(|v| !v.is_finite()) {
                                return Err(SceneError::NonFinite {
                                    path: path.clone(),
                                    what: format!(
                                        "the {what} texture transform of material {}",
                                        m.index().unwrap_or(0)
                                    ),
                                });
                            }
                            let index = self.textures.iter().position(|&t| t == used);
                            Ok(index.map_or(NO_TEXTURE, |i| i as u32))
                        }
                        Err(tex_coord) => {
                            warnings.push(format!(
                                "material {} takes its {what} texture from TEXCOORD_{tex_coord}; \
                                 only TEXCOORD_0 is read, so its {factor} is used alone",
                                m.index().unwrap_or(0),
                            ));
                            Ok(NO_TEXTURE)
                        }
                    },
                };
            let base_color_texture =
                texture(pbr.base_color_texture(), "base-colour", "baseColorFactor")?;
            let emissive_texture = texture(m.emissive_texture(), "emissive", "emissiveFactor")?;
            let metallic_roughness_texture = texture(
                pbr.metallic_roughness_texture(),
                "metallic-roughness",
                "metallicFactor and roughnessFactor",
            )?;
            let material = Material {
                base_color: [r, g, b],
                metallic: pbr.metallic_factor().clamp(0.0, 1.0),
                emission: emission.to_array(),
                roughness: pbr.roughness_factor().clamp(0.0, 1.0),
                base_color_texture,
                emissive_texture,
                metallic_roughness_texture,
                alpha_cutoff: alpha_cutoff(m.alpha_mode(), m.alpha_cutoff(), a),
            };
            let values = [
                r,
                g,
                b,
                a,
                material.metallic,
                material.roughness,
                emission.x,
                emission.y,
                emission.z,
            ];
            if values.iter().any(|v| !v.is_finite()) {
                return Err(SceneError::NonFinite {
                    path: path.clone(),
                    what: format!("a factor of material {}", m.index().unwrap_or(0)),
                });
            }
            materials.push(material);
        }
        Ok(materials)
    }

    /// Warns of what the file uses and the renderer does not read, so that a scene that looks
    /// wrong says why: extensions other than [`READ_EXTENSIONS`] (transmission, clearcoat,
    /// unlit materials, …), alpha mode `BLEND` (rendered opaque), point
    /// and line primitives (skipped). One sentence per feature, naming the materials or meshes
    /// that use it.
    fn unread_features(&self, warnings: &mut Vec<String>) {
        let document = &self.document;
        for extension in document.extensions_used() {
            if !READ_EXTENSIONS.contains(&extension) {
                warnings.push(format!(
                    "the file uses the extension {extension}, which the renderer does not read"
                ));
            }
        }
        let materials_with = |has: &dyn Fn(&gltf::Material) -> bool| -> Option<String> {
            let which: Vec<String> = document
                .materials()
                .filter(|m| has(m))
                .map(|m| m.index().unwrap_or(0).to_string())
                .collect();
            match which.len() {
                0 => None,
                1 => Some(format!("material {}", which[0])),
                _ => Some(format!("materials {}", which.join(", "))),
            }
        };
        if let Some(which) = materials_with(&|m| m.alpha_mode() == gltf::material::AlphaMode::Blend)
        {
            warnings.push(format!(
                "{which}: alphaMode BLEND is not read; the surface is rendered opaque"
            ));
        }
        for animation in document.animations() {
            let mut reasons: Vec<String> = Vec::new();
            let mut unplayed = 0;
            for channel in animation.channels() {
                if let Some(reason) = self.unplayed_channel(&channel) {
                    unplayed += 1;
                    if !reasons.contains(&reason) {
                        reasons.push(reason);
                    }
                }
            }
            if unplayed > 0 {
                warnings.push(format!(
                    "animation {}: {unplayed} of its {} channels are not played ({}); their \
                     nodes keep their rest transforms",
                    animation.index(),
                    animation.channels().count(),
                    reasons.join(", ")
                ));
            }
        }
        let lines: Vec<String> = document
            .meshes()
            .filter(|mesh| mesh.primitives().any(|p| !is_triangles(p.mode())))
            .map(|mesh| mesh.index().to_string())
            .collect();
        if !lines.is_empty() {
            warnings.push(format!(
                "mesh{} {}: points and lines have no area and are not rendered",
                if lines.len() > 1 { "es" } else { "" },
                lines.join(", ")
            ));
        }
    }

    /// The camera of `node` placed by its `world` transform, if it is a perspective one.
    fn node_camera(&self, node: &gltf::Node, world: Mat4) -> Result<Option<Camera>, SceneError> {
        let Some(c) = node.camera() else {
            return Ok(None);
        };
        let gltf::camera::Projection::Perspective(p) = c.projection() else {
            return Ok(None);
        };
        let yfov = p.yfov();
        if !(yfov > 0.0 && yfov < core::f32::consts::PI) {
            return Err(SceneError::NonFinite {
                path: self.path.clone(),
                what: format!("the yfov of camera {}", c.index()),
            });
        }
        Ok(Some(Camera {
            position: world.transform_point3(Vec3::ZERO),
            right: world.transform_vector3(Vec3::X).normalize(),
            up: world.transform_vector3(Vec3::Y).normalize(),
            forward: world.transform_vector3(Vec3::NEG_Z).normalize(),
            yfov,
        }))
    }

    /// Gives `scene` the triangles' attributes (in BVH order) when its materials use textures
    /// or a primitive has vertex colours, and the file's textures.
    fn attach_attributes(&self, scene: &mut Scene, attributes: &[TriangleAttributes]) {
        let coloured = attributes
            .iter()
            .any(|a| a.color != [TriangleAttributes::WHITE; 3]);
        if self.images.is_empty() && !coloured {
            // No texture and opaque white vertices: every alpha is the factor's, which
            // passes the masks left (the loader dropped those it cuts out).
            for m in &mut scene.materials {
                m.alpha_cutoff = 0.0;
            }
            return;
        }
        scene.attributes = scene
            .bvh
            .source
            .iter()
            .map(|&i| attributes[i as usize])
            .collect();
        let mut offsets = Vec::new();
        for (_, _, _, texels) in &self.images {
            offsets.push(scene.texels.len() as u32);
            scene.texels.extend_from_slice(texels);
        }
        for &TextureUse { image, map, wrap } in &self.textures {
            let k = self.images.iter().position(|i| i.0 == image);
            let k = k.expect("SceneFile::open packs the image of every texture");
            scene.textures.push(TextureInfo {
                offset: offsets[k],
                width: self.images[k].1,
                height: self.images[k].2,
                wrap,
                map,
            });
        }
    }

    /// Appends the world-space triangles of `mesh` under the transform `world`, and their
    /// texture coordinates (zero where the material has no texture).
    fn push_mesh(
        &self,
        mesh: &gltf::Mesh,
        world: Mat4,
        materials: &[Material],
        out: &mut Vec<Triangle>,
        out_attributes: &mut Vec<TriangleAttributes>,
    ) -> Result<(), SceneError> {
        let path = &self.path;
        let mirrored = world.determinant() < 0.0;
        for primitive in mesh.primitives() {
            if !is_triangles(primitive.mode()) {
                continue;
            }
            let reader = primitive.reader(|b| self.buffers.get(b.index()).map(|d| &d.0[..]));
            let positions: Vec<Vec3> = reader
                .read_positions()
                .ok_or_else(|| SceneError::MissingPositions {
                    path: path.clone(),
                    mesh: mesh.index(),
                })?
                .map(|p| world.transform_point3(Vec3::from(p)))
                .collect();
            if positions.iter().any(|p| !p.is_finite()) {
                return Err(SceneError::NonFinite {
                    path: path.clone(),
                    what: format!("a vertex position of mesh {}", mesh.index()),
                });
            }
            let indices: Vec<u32> = match reader.read_indices() {
                Some(i) => i.into_u32().collect(),
                None => (0..positions.len() as u32).collect(),
            };
            let indices = triangle_list(primitive.mode(), indices);
            // glTF's default material is our material 0; file materials start at 1.
            let material = primitive.material().index().map_or(0, |i| i as u32 + 1);
            if materials[material as usize].alpha_cutoff > 1.0 {
                // A mask whose factor alone is below its cutoff: cut out everywhere.
                continue;
            }
            let tex_coords: Vec<[f32; 2]> = match reader
                .read_tex_coords(0)
                .filter(|_| materials[material as usize].is_textured())
            {
                Some(t) => t.into_f32().collect(),
                None => Vec::new(),
            };
            let colors: Vec<[f32; 4]> = match reader.read_colors(0) {
                Some(c) => c.into_rgba_f32().collect(),
                None => Vec::new(),
            };
            if colors.iter().flatten().any(|c| !c.is_finite()) {
                return Err(SceneError::NonFinite {
                    path: path.clone(),
                    what: format!("a vertex colour of mesh {}", mesh.index()),
                });
            }
            for t in indices.chunks_exact(3) {
                let vertex = |k: usize| {
                    positions
                        .get(t[k] as usize)
                        .copied()
                        .ok_or_else(|| SceneError::Unreadable {
                            path: path.clone(),
                            reason: format!("mesh {} has an index past its vertices", mesh.index()),
                        })
                };
                let (a, mut b, mut c) = (vertex(0)?, vertex(1)?, vertex(2)?);
                let uv = |k: usize| tex_coords.get(t[k] as usize).copied().unwrap_or_default();
                let color = |k: usize| {
                    colors
                        .get(t[k] as usize)
                        .map_or(TriangleAttributes::WHITE, |&c| {
                            TriangleAttributes::pack_color(c)
                        })
                };
                let mut attributes = TriangleAttributes {
                    uv: [uv(0), uv(1), uv(2)],
                    color: [color(0), color(1), color(2)],
                };
                if mirrored {
                    core::mem::swap(&mut b, &mut c);
                    attributes.uv.swap(1, 2);
                    attributes.color.swap(1, 2);
                }
                let tri = Triangle::new(a, b, c, material);
                if tri.area() > 0.0 {
                    out.push(tri);
                    out_attributes.push(attributes);
                }
            }
        }
        Ok(())
    }

    /// Every node's local transform at `time`: its TRS (or matrix) with animated channels
    /// replaced by their values at `time`.
    fn local_transforms(&self, time: f32) -> Result<Vec<Mat4>, SceneError> {
        let mut trs: Vec<Option<(Vec3, Quat, Vec3)>> = self
            .document
            .nodes()
            .map(|n| match n.transform() {
                gltf::scene::Transform::Decomposed {
                    translation,
                    rotation,
                    scale,
                } => Some((
                    Vec3::from(translation),
                    Quat::from_array(rotation),
                    Vec3::from(scale),
                )),
                gltf::scene::Transform::Matrix { .. } => None,
            })
            .collect();
        for animation in self.document.animations() {
            let unsupported = |reason: String| SceneError::UnsupportedAnimation {
                path: self.path.clone(),
                animation: animation.index(),
                reason,
            };
            for channel in animation.channels() {
                if self.unplayed_channel(&channel).is_some() {
                    continue;
                }
                let node = channel.target().node().index();
                let interpolation = channel.sampler().interpolation();
                let Some(node_trs) = trs[node].as_mut() else {
                    continue;
                };
                let reader = channel.reader(|b| self.buffers.get(b.index()).map(|d| &d.0[..]));
                let times: Vec<f32> = reader
                    .read_inputs()
                    .ok_or_else(|| unsupported("unreadable keyframe times".to_owned()))?
                    .collect();
                let outputs = reader
                    .read_outputs()
                    .ok_or_else(|| unsupported("unreadable keyframe values".to_owned()))?;
                let values: Vec<[f32; 4]> = match (channel.target().property(), outputs) {
                    (Property::Translation, ReadOutputs::Translations(v))
                    | (Property::Scale, ReadOutputs::Scales(v)) => {
                        v.map(|[x, y, z]| [x, y, z, 0.0]).collect()
                    }
                    (Property::Rotation, ReadOutputs::Rotations(v)) => v.into_f32().collect(),
                    _ => {
                        return Err(unsupported(
                            "keyframe values that do not match the channel's property".to_owned(),
                        ));
                    }
                };
                if times.is_empty() || times.len() != values.len() {
                    return Err(unsupported(
                        "keyframe times and values differ in count".to_owned(),
                    ));
                }
                let rotation = channel.target().property() == Property::Rotation;
                let step = interpolation == Interpolation::Step;
                let v = sample_keyframes(&times, &values, time, step, rotation);
                match channel.target().property() {
                    Property::Translation => node_trs.0 = Vec3::new(v[0], v[1], v[2]),
                    Property::Rotation => node_trs.1 = Quat::from_array(v).normalize(),
                    _ => node_trs.2 = Vec3::new(v[0], v[1], v[2]),
                }
            }
        }
        Ok(self
            .document
            .nodes()
            .zip(trs)
            .map(|(n, t)| match t {
                Some((translation, rotation, scale)) => {
                    Mat4::from_scale_rotation_translation(scale, rotation, translation)
                }
                None => Mat4::from_cols_array_2d(&n.transform().matrix()),
            })
            .collect())
    }
}

/// The textures the document's materials read from `TEXCOORD_0` (base-colour, emissive and
/// metallic-roughness textures) as [`texture_use`] gives them, each once, in the order of
/// first use.
fn used_textures(document: &gltf::Document) -> Vec<TextureUse> {
    let mut used = Vec::new();
    for m in document.materials() {
        let pbr = m.pbr_metallic_roughness();
        for info in [
            pbr.base_color_texture(),
            m.emissive_texture(),
            pbr.metallic_roughness_texture(),
        ] {
            if let Some(Ok(texture)) = info.as_ref().map(texture_use)
                && !used.contains(&texture)
            {
                used.push(texture);
            }
        }
    }
    used
}

/// What a material's texture slot reads: the image, the map of texture coordinates
/// (`KHR_texture_transform`, [`TextureInfo::transform`]) and the sampler's wrap modes; or the
/// texture coordinate set it reads when that is not `TEXCOORD_0` (the extension's `texCoord`
/// overrides the slot's).
fn texture_use(info: &gltf::texture::Info) -> Result<TextureUse, u32> {
    let transform = info.texture_transform();
    let tex_coord = transform.as_ref().and_then(|t| t.tex_coord());
    let tex_coord = tex_coord.unwrap_or(info.tex_coord());
    if tex_coord != 0 {
        return Err(tex_coord);
    }
    let map = transform.map_or(TextureInfo::IDENTITY, |t| {
        TextureInfo::transform(t.offset(), t.rotation(), t.scale())
    });
    let mode = |m: gltf::texture::WrappingMode| match m {
        gltf::texture::WrappingMode::ClampToEdge => WRAP_CLAMP,
        gltf::texture::WrappingMode::MirroredRepeat => WRAP_MIRROR,
        gltf::texture::WrappingMode::Repeat => WRAP_REPEAT,
    };
    let sampler = info.texture().sampler();
    Ok(TextureUse {
        image: info.texture().source().index(),
        map,
        wrap: mode(sampler.wrap_s()) | mode(sampler.wrap_t()) << 16,
    })
}

/// Whether primitives of `mode` have area (triangles, strips and fans) and so are rendered.
/// The camera of [`SceneFile::with_auto_camera`] for `triangles` (not empty): 45° vertical
/// field of view, looking down −Z at the centre of their bounding box from the distance at
/// which the box's bounding sphere just fits the field of view.
fn auto_camera(triangles: &[Triangle]) -> Camera {
    let (lo, hi) = bounds(triangles);
    let yfov = core::f32::consts::FRAC_PI_4;
    let centre = 0.5 * (lo + hi);
    let radius = (0.5 * (hi - lo).length()).max(1e-3);
    Camera {
        position: centre + Vec3::Z * radius / (0.5 * yfov).sin(),
        right: Vec3::X,
        up: Vec3::Y,
        forward: Vec3::NEG_Z,
        yfov,
    }
}

/// The corners (lowest, highest) of the axis-aligned box around `triangles`' vertices.
fn bounds(triangles: &[Triangle]) -> (Vec3, Vec3) {
    triangles
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), t| {
            let v0 = Vec3::from(t.v0);
            let (v1, v2) = (v0 + Vec3::from(t.e1), v0 + Vec3::from(t.e2));
            (lo.min(v0).min(v1).min(v2), hi.max(v0).max(v1).max(v2))
        })
}

/// Reads the environment map `map` for the scene file `path`, turned by `degrees` about +Y
/// ([`EnvironmentMap::with_rotation`]), as [`SceneError::EnvironmentMap`] (naming both) when it
/// cannot.
fn open_environment_map(
    path: &Path,
    map: &Path,
    degrees: f32,
) -> Result<Arc<EnvironmentMap>, SceneError> {
    EnvironmentMap::open(map)
        .map(|m| Arc::new(m.with_rotation(degrees.to_radians())))
        .map_err(|reason| SceneError::EnvironmentMap {
            path: path.to_path_buf(),
            reason,
        })
}

/// The value of `mcg.<key>` in the default scene's extras: `Some(None)` without one, `None`
/// where the extras are not JSON.
fn mcg_extra(document: &gltf::Document, key: &str) -> Option<Option<serde_json::Value>> {
    let scene = document
        .default_scene()
        .or_else(|| document.scenes().next())?;
    let Some(raw) = scene.extras() else {
        return Some(None);
    };
    let mut extras: serde_json::Value = serde_json::from_str(raw.get()).ok()?;
    Some(
        extras
            .pointer_mut(&format!("/mcg/{key}"))
            .map(serde_json::Value::take),
    )
}

/// The numbers of a JSON array, as `f32`; `None` where it is not an array of numbers.
fn json_numbers(value: &serde_json::Value) -> Option<Vec<f32>> {
    value
        .as_array()?
        .iter()
        .map(|c| c.as_f64().map(|c| c as f32))
        .collect()
}

/// The environment that the default scene's extras name (see [`SceneFile::open`]): `Err` of
/// a uniform radiance (`mcg.environment` as three finite non-negative numbers; zero without
/// one) or `Ok` of an environment map's file name (`mcg.environment` as a string, relative to
/// the glTF file); `None` for a malformed one.
fn extras_environment(document: &gltf::Document) -> Option<Result<PathBuf, Vec3>> {
    let Some(value) = mcg_extra(document, "environment")? else {
        return Some(Err(Vec3::ZERO));
    };
    if let Some(file) = value.as_str() {
        return Some(Ok(PathBuf::from(file)));
    }
    match json_numbers(&value)?[..] {
        [r, g, b] if [r, g, b].iter().all(|c| c.is_finite() && *c >= 0.0) => {
            Some(Err(Vec3::new(r, g, b)))
        }
        _ => None,
    }
}

/// The number `mcg.<key>` in the default scene's extras: 0 without one, `None` where it is
/// not a finite number.
fn extras_number(document: &gltf::Document, key: &str) -> Option<f32> {
    match mcg_extra(document, key)? {
        None => Some(0.0),
        Some(value) => value.as_f64().map(|v| v as f32).filter(|v| v.is_finite()),
    }
}

/// The portals that the default scene's extras name (`mcg.portals`: a list of
/// `[cx, cy, cz, ux, uy, uz, vx, vy, vz]`, a corner and two edges in world space, see
/// [`Portal::new`]): empty without them, `None` for a malformed list.
fn extras_portals(document: &gltf::Document) -> Option<Vec<Portal>> {
    let Some(list) = mcg_extra(document, "portals")? else {
        return Some(Vec::new());
    };
    list.as_array()?
        .iter()
        .map(|p| {
            let [cx, cy, cz, ux, uy, uz, vx, vy, vz] = json_numbers(p)?[..] else {
                return None;
            };
            Portal::new(
                Vec3::new(cx, cy, cz),
                Vec3::new(ux, uy, uz),
                Vec3::new(vx, vy, vz),
            )
        })
        .collect()
}

/// [`Material::alpha_cutoff`] of a material with alpha mode `mode`, the file's `alphaCutoff`
/// `cutoff` (glTF's default 0.5 where it has none) and the alpha `factor` of its
/// `baseColorFactor`: `cutoff / factor` for MASK (+∞ where the factor is 0 and the cutoff is
/// not, so that nothing passes), 0 for OPAQUE and BLEND (rendered opaque).
fn alpha_cutoff(mode: gltf::material::AlphaMode, cutoff: Option<f32>, factor: f32) -> f32 {
    let cutoff = cutoff.unwrap_or(0.5).max(0.0);
    if mode != gltf::material::AlphaMode::Mask || cutoff == 0.0 {
        0.0
    } else if factor > 0.0 {
        cutoff / factor
    } else {
        f32::INFINITY
    }
}

fn is_triangles(mode: gltf::mesh::Mode) -> bool {
    use gltf::mesh::Mode;
    matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    )
}

/// The vertex indices of a triangle primitive of `mode` as a list of triangles (three
/// indices each), each in its primitive's winding: for a strip, triangle `i` is
/// `(vᵢ, vᵢ₊₁₊ᵢ﹪₂, vᵢ₊₂₋ᵢ﹪₂)`, for a fan `(vᵢ₊₁, vᵢ₊₂, v₀)` (glTF 2.0 specification,
/// section "Topology Types"). A strip or fan of fewer than three vertices has no triangle.
fn triangle_list(mode: gltf::mesh::Mode, indices: Vec<u32>) -> Vec<u32> {
    use gltf::mesh::Mode;
    let count = indices.len().saturating_sub(2);
    match mode {
        Mode::TriangleStrip => (0..count)
            .flat_map(|i| {
                let odd = i % 2;
                [indices[i], indices[i + 1 + odd], indices[i + 2 - odd]]
            })
            .collect(),
        Mode::TriangleFan => (0..count)
            .flat_map(|i| [indices[i + 1], indices[i + 2], indices[0]])
            .collect(),
        _ => indices,
    }
}

/// The keyframe value at `time`: clamped before the first and after the last key; between
/// keys the earlier value (STEP) or the linear blend (LINEAR; for a `rotation`, the later
/// quaternion is first moved to the earlier one's hemisphere, and the caller normalises: a
/// normalised lerp).
fn sample_keyframes(
    times: &[f32],
    values: &[[f32; 4]],
    time: f32,
    step: bool,
    rotation: bool,
) -> [f32; 4] {
    let next = times.partition_point(|&t| t <= time);
    if next == 0 {
        return values[0];
    }
    if next == times.len() {
        return values[times.len() - 1];
    }
    let (a, b) = (values[next - 1], values[next]);
    if step {
        return a;
    }
    let s = (time - times[next - 1]) / (times[next] - times[next - 1]);
    let dot: f32 = (0..4).map(|i| a[i] * b[i]).sum();
    let sign = if rotation && dot < 0.0 { -1.0 } else { 1.0 };
    core::array::from_fn(|i| a[i] + s * (sign * b[i] - a[i]))
}

/// An 8-bit glTF image's texels as packed RGBA8 ([`Scene::texels`]); grey images are
/// replicated to RGB, and images without alpha get an opaque one.
fn rgba8(data: &gltf::image::Data) -> Result<Vec<u32>, String> {
    use gltf::image::Format;
    let channels = match data.format {
        Format::R8 => 1,
        Format::R8G8 => 2,
        Format::R8G8B8 => 3,
        Format::R8G8B8A8 => 4,
        other => return Err(format!("{other:?} texels; only 8-bit images are supported")),
    };
    if data.pixels.len() != (data.width * data.height) as usize * channels || data.width == 0 {
        return Err("the pixel data does not match the image size".to_owned());
    }
    Ok(data
        .pixels
        .chunks_exact(channels)
        .map(|p| {
            let [r, g, b, a] = match *p {
                [grey] => [grey, grey, grey, u8::MAX],
                [grey, alpha] => [grey, grey, grey, alpha],
                [r, g, b] => [r, g, b, u8::MAX],
                [r, g, b, a, ..] => [r, g, b, a],
                [] => [0; 4],
            };
            u32::from_le_bytes([r, g, b, a])
        })
        .collect())
}

/// [`srgb_to_linear`] of every byte value `b / 255`.
static SRGB_BYTES: std::sync::LazyLock<[f32; 256]> =
    std::sync::LazyLock::new(|| core::array::from_fn(|b| srgb_to_linear(b as f32 / 255.0)));

/// The sRGB electro-optical transfer function (IEC 61966-2-1): an encoded value in [0, 1] to
/// linear.
#[must_use]
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

impl Scene {
    /// Builds the BVH over `triangles` and the emitter table; `None` when no triangle emits.
    #[must_use]
    pub fn new(
        camera: Camera,
        triangles: &[Triangle],
        materials: Vec<Material>,
        warnings: Vec<String>,
    ) -> Option<Self> {
        Self::new_lit(camera, triangles, materials, warnings, Vec3::ZERO)
    }

    /// [`Scene::new`] lit by a uniform environment of radiance `environment` too
    /// ([`Scene::environment`]); `None` when no triangle emits and the environment is black.
    #[must_use]
    pub fn new_lit(
        camera: Camera,
        triangles: &[Triangle],
        materials: Vec<Material>,
        warnings: Vec<String>,
        environment: Vec3,
    ) -> Option<Self> {
        let bvh = Bvh::build(triangles);
        let mut emitters = Vec::new();
        let mut power = Vec::new();
        for (i, t) in bvh.triangles.iter().enumerate() {
            let p = t.area() * luminance(materials[t.material as usize].emission());
            if p > 0.0 {
                emitters.push(i as u32);
                power.push(p);
            }
        }
        if emitters.is_empty() && !(luminance(environment) > 0.0) {
            return None;
        }
        let emitter_triangles: Vec<Triangle> = emitters
            .iter()
            .map(|&i| Triangle {
                source: i,
                ..bvh.triangles[i as usize]
            })
            .collect();
        let mut scene = Self {
            camera,
            emitter_bvh: Bvh::build(&emitter_triangles),
            bvh,
            materials,
            emitters,
            emitter_cdf: Vec::new(),
            environment: Vec3::ZERO,
            environment_pmf: 0.0,
            environment_map: None,
            portals: Vec::new(),
            attributes: Vec::new(),
            textures: Vec::new(),
            texels: Vec::new(),
            warnings,
        };
        scene.set_emitter_power(&power);
        scene.set_environment(environment);
        Some(scene)
    }

    /// Lights the scene by a uniform environment of radiance `radiance` ([`Scene::environment`];
    /// zero for none; with an [`Scene::environment_map`], the map's factor) and shares light selection between it and the emitting triangles
    /// ([`Scene::environment_pmf`]; the triangles keep their ratios). A scene without
    /// emitting triangles and a black environment renders black.
    pub fn set_environment(&mut self, radiance: Vec3) {
        let lit = luminance(radiance) > 0.0;
        let pmf = if self.emitters.is_empty() {
            1.0
        } else if lit {
            ENVIRONMENT_PICK
        } else {
            0.0
        };
        if !self.emitters.is_empty() {
            let scale = (1.0 - pmf) / (1.0 - self.environment_pmf);
            for &i in &self.emitters {
                self.bvh.triangles[i as usize].emitter_pmf *= scale;
            }
            for copy in &mut self.emitter_bvh.triangles {
                copy.emitter_pmf = self.bvh.triangles[copy.source as usize].emitter_pmf;
            }
        }
        self.environment = if lit { radiance } else { Vec3::ZERO };
        self.environment_pmf = pmf;
    }

    /// Lights the scene by the environment map `map` ([`Scene::environment_map`]) at its own
    /// radiance ([`Scene::environment`] = 1), sharing light selection as
    /// [`Scene::set_environment`] does.
    pub fn set_environment_map(&mut self, map: Arc<EnvironmentMap>) {
        self.environment_map = Some(map);
        self.set_environment(Vec3::ONE);
    }

    /// The radiance seen looking along the unit direction `d` out of the scene:
    /// [`Scene::environment`], times the [`Scene::environment_map`]'s texel where there is one.
    #[must_use]
    pub fn environment_radiance(&self, d: Vec3) -> Vec3 {
        match &self.environment_map {
            Some(map) => self.environment * map.radiance(d),
            None => self.environment,
        }
    }

    /// A direction of a light sample of the environment at `origin`, a vertex of normal
    /// `normal`, from uniforms `u` (`u.x` picks a portal, `u.y` and `u.z` the direction), and
    /// its solid-angle density without [`Scene::environment_pmf`]
    /// ([`Scene::environment_pdf`]); `None` when it has no density. Directions come from the
    /// [`Scene::environment_map`] where there is one ([`EnvironmentMap::sample`]); for a
    /// uniform environment, toward a uniform point of a portal picked in proportion to its
    /// area ([`Portal::sample`]) where the scene has [`Scene::portals`], else
    /// cosine-distributed about `normal` (the radiance times the Lambertian cosine).
    #[must_use]
    pub fn sample_environment(&self, origin: Vec3, normal: Vec3, u: Vec3) -> Option<(Vec3, f32)> {
        let uv = Vec2::new(u.y, u.z);
        if let Some(map) = &self.environment_map {
            return map.sample(uv);
        }
        if self.portals.is_empty() {
            let (wi, pdf) = mcg_markov_guide::cosine_hemisphere(normal, uv);
            return (pdf > 0.0).then_some((wi, pdf));
        }
        let mut v = u.x;
        let last = self.portals.len() - 1;
        let mut k = 0;
        while k < last && v >= self.portals[k].pmf {
            v -= self.portals[k].pmf;
            k += 1;
        }
        let (wi, _) = self.portals[k].sample(origin, uv)?;
        let pdf = self.environment_pdf(origin, normal, wi);
        (pdf > 0.0 && pdf.is_finite()).then_some((wi, pdf))
    }

    /// The density with which [`Scene::sample_environment`] at `origin`, a vertex of normal
    /// `normal`, draws the unit direction `d` (without [`Scene::environment_pmf`]): the map's,
    /// Σ pmf × [`Portal::pdf`] over the portals the ray crosses (portals can overlap as seen
    /// from `origin`), or the cosine's.
    #[must_use]
    pub fn environment_pdf(&self, origin: Vec3, normal: Vec3, d: Vec3) -> f32 {
        if let Some(map) = &self.environment_map {
            map.pdf(d)
        } else if self.portals.is_empty() {
            mcg_markov_guide::cosine_hemisphere_pdf(normal, d)
        } else {
            self.portals.iter().map(|p| p.pmf * p.pdf(origin, d)).sum()
        }
    }

    /// Makes `portals` the scene's [`Scene::portals`], each picked in proportion to its area.
    pub fn set_portals(&mut self, mut portals: Vec<Portal>) {
        let total: f32 = portals.iter().map(|p| p.area).sum();
        for p in &mut portals {
            p.pmf = p.area / total;
        }
        self.portals = portals;
    }

    /// Light selection proportional to `power` (one value per [`Scene::emitters`], all
    /// positive): [`Scene::emitter_cdf`] and the emitters' [`Triangle::emitter_pmf`] (which
    /// leave [`Scene::environment_pmf`] to the environment), in the scene's tree and in the
    /// emitters' tree of copies (whose shape does not depend on it).
    fn set_emitter_power(&mut self, power: &[f32]) {
        let total: f64 = power.iter().map(|&p| f64::from(p)).sum();
        let share = f64::from(1.0 - self.environment_pmf);
        let mut acc = 0.0;
        self.emitter_cdf.clear();
        for (&i, &p) in self.emitters.iter().zip(power) {
            acc += f64::from(p);
            self.emitter_cdf.push((acc / total) as f32);
            self.bvh.triangles[i as usize].emitter_pmf = (share * f64::from(p) / total) as f32;
        }
        if let Some(last) = self.emitter_cdf.last_mut() {
            *last = 1.0;
        }
        for copy in &mut self.emitter_bvh.triangles {
            copy.emitter_pmf = self.bvh.triangles[copy.source as usize].emitter_pmf;
        }
    }

    /// Weighs light selection by each emitter's emissive texture too, once textures are
    /// attached: an emitter's power becomes its area × the mean luminance of its textured
    /// emission at [`EMISSION_PROBES`] barycentric points (the centroids of its 4 × 4
    /// subdivision's upright triangles), but at least [`MIN_TEXTURE_POWER`] × its area ×
    /// the luminance of its factor, so that every triangle that may emit keeps a positive
    /// probability and light sampling stays unbiased wherever the probes miss a bright texel.
    /// Emitters without an emissive texture keep area × the factor's luminance. Without it a
    /// mesh whose emissive texture is dark but for a few windows sends most light samples to
    /// dark triangles.
    pub fn weigh_emitters_by_texture(&mut self) {
        if !self
            .materials
            .iter()
            .any(|m| m.emissive_texture != NO_TEXTURE)
        {
            return;
        }
        let power: Vec<f32> = self
            .emitters
            .iter()
            .map(|&i| {
                let t = self.bvh.triangles[i as usize];
                let material = &self.materials[t.material as usize];
                let factor = luminance(material.emission());
                if material.emissive_texture == NO_TEXTURE {
                    return t.area() * factor;
                }
                let probes: f32 = EMISSION_PROBES
                    .iter()
                    .map(|&(b1, b2)| {
                        let hit = Hit {
                            t: 0.0,
                            triangle: i,
                            b1,
                            b2,
                        };
                        luminance(self.material_at(&hit).emission())
                    })
                    .sum();
                let mean = probes / EMISSION_PROBES.len() as f32;
                t.area() * mean.max(MIN_TEXTURE_POWER * factor)
            })
            .collect();
        self.set_emitter_power(&power);
    }

    /// The material at a hit, with its textures (where it has them) looked up at the hit's
    /// texture coordinates ([`TextureInfo`]: mapped, wrapped, nearest texel) and multiplied into
    /// `base_color` and `emission` (sRGB-decoded), `roughness` (green) and `metallic` (blue;
    /// both linear).
    #[must_use]
    pub fn material_at(&self, hit: &Hit) -> Material {
        let mut m = *self.material(hit.triangle);
        let Some(attributes) = self.attributes.get(hit.triangle as usize) else {
            return m;
        };
        let color = attributes.color_at(hit.b1, hit.b2);
        m.base_color = (Vec3::from(m.base_color) * color).to_array();
        if !m.is_textured() {
            return m;
        }
        let uv = attributes.uv_at(hit.b1, hit.b2);
        if let Some(texel) = self.texel(m.base_color_texture, uv) {
            for (b, t) in m.base_color.iter_mut().zip(texel) {
                *b *= SRGB_BYTES[usize::from(t)];
            }
        }
        if let Some(texel) = self.texel(m.emissive_texture, uv) {
            for (e, t) in m.emission.iter_mut().zip(texel) {
                *e *= SRGB_BYTES[usize::from(t)];
            }
        }
        if let Some([_, g, b, _]) = self.texel(m.metallic_roughness_texture, uv) {
            m.roughness *= f32::from(g) / 255.0;
            m.metallic *= f32::from(b) / 255.0;
        }
        m
    }

    /// Whether triangle `triangle` (leaf order) is a surface at barycentrics (`b1`, `b2`):
    /// always for an opaque material; for an alpha mask (glTF 2.0, "Alpha Coverage",
    /// `alphaMode` MASK) where the base-colour texture's alpha × the vertex colour's alpha
    /// reaches [`Material::alpha_cutoff`]. Rays pass through the rest, light samples that
    /// land there carry nothing, and nothing is emitted there.
    #[inline]
    #[must_use]
    pub fn is_surface_at(&self, triangle: u32, b1: f32, b2: f32) -> bool {
        let m = self.material(triangle);
        if m.alpha_cutoff <= 0.0 {
            return true;
        }
        let Some(a) = self.attributes.get(triangle as usize) else {
            return true;
        };
        let texel = self
            .texel(m.base_color_texture, a.uv_at(b1, b2))
            .map_or(1.0, |[.., alpha]| f32::from(alpha) / 255.0);
        texel * a.alpha_at(b1, b2) >= m.alpha_cutoff
    }

    /// The closest surface the ray `origin + t·direction` hits, `t ∈ (t_min, t_max)`:
    /// [`Bvh::intersect`] through the holes of alpha masks ([`Scene::is_surface_at`]).
    #[must_use]
    pub fn intersect(&self, origin: Vec3, direction: Vec3, t_min: f32, t_max: f32) -> Option<Hit> {
        self.bvh
            .intersect_where(origin, direction, t_min, t_max, |i, b1, b2| {
                self.is_surface_at(i, b1, b2)
            })
    }

    /// Whether a surface blocks the ray within `(t_min, t_max)` (shadow rays):
    /// [`Bvh::occluded`] through the holes of alpha masks ([`Scene::is_surface_at`]).
    #[must_use]
    pub fn occluded(&self, origin: Vec3, direction: Vec3, t_min: f32, t_max: f32) -> bool {
        self.bvh
            .occluded_where(origin, direction, t_min, t_max, |i, b1, b2| {
                self.is_surface_at(i, b1, b2)
            })
    }

    /// The closest emitter whose front face the ray from `origin` along the unit `direction`
    /// meets, in [`Scene::emitter_bvh`] (the hit's triangle indexes that tree), through the
    /// holes of alpha masks ([`Scene::is_surface_at`] of its [`Triangle::source`]).
    #[must_use]
    pub fn intersect_emitter(&self, origin: Vec3, direction: Vec3) -> Option<Hit> {
        let tree = &self.emitter_bvh;
        tree.intersect_front_where(origin, direction, 0.0, f32::INFINITY, |i, b1, b2| {
            self.is_surface_at(tree.triangles[i as usize].source, b1, b2)
        })
    }

    /// The emitted radiance of the emitters' tree's triangle `emitter` at barycentrics
    /// (`b1`, `b2`): its material's emission with the emissive texture of the same triangle
    /// in the scene's tree ([`Triangle::source`]).
    #[must_use]
    pub fn emitter_emission(&self, emitter: u32, b1: f32, b2: f32) -> Vec3 {
        let triangle = self.emitter_bvh.triangles[emitter as usize].source;
        let hit = Hit {
            t: 0.0,
            triangle,
            b1,
            b2,
        };
        self.material_at(&hit).emission()
    }

    /// Texture `texture`'s RGBA bytes at texture coordinates `uv` (mapped by
    /// [`TextureInfo::map`], wrapped by [`TextureInfo::wrap`], nearest texel); `None` for
    /// [`NO_TEXTURE`].
    fn texel(&self, texture: u32, uv: [f32; 2]) -> Option<[u8; 4]> {
        let tex = self.textures.get(texture as usize)?;
        let [u, v] = tex.mapped(uv);
        let x = wrapped_texel(u, tex.wrap & 0xffff, tex.width);
        let y = wrapped_texel(v, tex.wrap >> 16, tex.height);
        let index = tex.offset + y * tex.width + x;
        Some(self.texels[index as usize].to_le_bytes())
    }

    /// FNV-1a over everything that decides the scene's image — the camera, the triangles (with
    /// their materials' indices and light-selection weights), materials, attributes, textures
    /// and texels, the environment with its map and rotation, and the portals — so that a
    /// cached render of the scene is found again only for the same scene. The triangles and
    /// their attributes in the file's order ([`Bvh::input_order`]), not the tree's leaf order, so
    /// that another tree over the same scene keeps its fingerprint.
    #[must_use]
    pub fn fingerprint(&self) -> u64 {
        let in_file_order = self.bvh.input_order();
        let triangles: Vec<Triangle> = in_file_order
            .iter()
            .map(|&leaf| self.bvh.triangles[leaf])
            .collect();
        let attributes: Vec<TriangleAttributes> = in_file_order
            .iter()
            .filter_map(|&leaf| self.attributes.get(leaf).copied())
            .collect();
        let c = &self.camera;
        let vectors = [c.position, c.right, c.up, c.forward, self.environment];
        let floats = vectors
            .iter()
            .flat_map(|v| v.to_array())
            .chain([c.yfov, self.environment_pmf])
            .chain(self.environment_map.iter().flat_map(|m| {
                m.texels()
                    .iter()
                    .flat_map(|t| t.to_array())
                    .chain([m.rotation(), m.width() as f32])
            }))
            .flat_map(f32::to_le_bytes);
        let bytes = bytemuck::cast_slice::<_, u8>(&triangles)
            .iter()
            .chain(bytemuck::cast_slice::<_, u8>(&self.materials))
            .chain(bytemuck::cast_slice::<_, u8>(&attributes))
            .chain(bytemuck::cast_slice::<_, u8>(&self.textures))
            .chain(bytemuck::cast_slice::<_, u8>(&self.texels))
            .chain(bytemuck::cast_slice::<_, u8>(&self.portals))
            .copied()
            .chain(floats);
        bytes.fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
            (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
        })
    }

    /// The material of triangle `triangle` (leaf order).
    #[must_use]
    pub fn material(&self, triangle: u32) -> &Material {
        &self.materials[self.bvh.triangles[triangle as usize].material as usize]
    }

    /// Picks a light from a uniform `u ∈ [0, 1)`: the environment where `u` is below
    /// [`Scene::environment_pmf`], else an emitting triangle by binary search in
    /// [`Scene::emitter_cdf`] for `u` rescaled to [0, 1) past it (`u` itself without an
    /// environment).
    #[must_use]
    pub fn pick_light(&self, u: f32) -> Light {
        let p = self.environment_pmf;
        if u < p || self.emitters.is_empty() {
            return Light::Environment;
        }
        let u = if p > 0.0 { (u - p) / (1.0 - p) } else { u };
        let k = self
            .emitter_cdf
            .partition_point(|&c| c <= u)
            .min(self.emitters.len() - 1);
        let t = self.emitters[k];
        Light::Triangle(t, self.bvh.triangles[t as usize].emitter_pmf)
    }
}
