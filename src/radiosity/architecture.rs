//! The paper's scene, generated (seed 000 §9, Fig. 7): a brightly lit living room with light
//! walls, joined by a door to a dimmer bedroom with darker walls; two cubes in the living
//! room and a bed in the bedroom; a window in each room's south wall and a skylight in the
//! living room's ceiling. The design parameters ([`PARAMETERS`]) are the window width, the
//! skylight size, the door width and the living room's ceiling tilt.
//!
//! **Fixed topology.** Every wall is a panel whose parameter rectangle is cut by breakpoints
//! (an opening's edges, the door's top) into blocks, and every block into cells: the *number*
//! of cells per block is fixed from the default parameters and the resolution, the breakpoints
//! move with the parameters. So every parameter vector gives the same triangles with other
//! vertex positions `g` — the deforming mesh of Table 2.
//!
//! Coordinates: metres, z up; the living room spans x ∈ [0, L₁], y ∈ [0, W]; the wall
//! between the rooms is x ∈ [L₁, L₁ + t]; the bedroom spans x ∈ [L₁ + t, L₁ + t + L₂]. The
//! living ceiling is hinged at the south wall (y = 0) and rises northwards:
//! `z = H + y·tan(tilt)`. Openings are meshed too (their faces carry [`FaceKind::Window`] or
//! [`FaceKind::Skylight`]), so the rooms are closed surfaces.
//!
//! [`PARAMETERS`]: super::scene::PARAMETERS

use std::collections::HashMap;

use glam::DVec3;

use super::error::RadiosityError;
use super::mesh::{FaceKind, SceneMesh};
use super::scene::{Parameters, SceneSpec, PARAMETERS};

/// Gap between furniture and walls (m), so that no two faces coincide.
const FURNITURE_GAP: f64 = 0.05;
/// Least distance (m) between an opening's edge and the edge of its wall.
const OPENING_MARGIN: f64 = 0.05;

/// What a block of a panel holds.
#[derive(Clone, Copy, PartialEq)]
enum Block {
    Surface,
    Omitted,
    Opening(FaceKind, &'static str),
}

/// A wall: breakpoints of its parameter rectangle, the blocks that are not plain surface, and
/// the map from (u, v) to space.
struct Panel<'a> {
    part: &'static str,
    albedo: [f64; 3],
    u: Vec<f64>,
    v: Vec<f64>,
    special: Vec<((usize, usize), Block)>,
    map: Box<dyn Fn(f64, f64) -> DVec3 + 'a>,
    /// The side the faces light (into the room, or out of a piece of furniture).
    inward: DVec3,
}

impl Panel<'_> {
    fn block(&self, bu: usize, bv: usize) -> Block {
        self.special.iter().find(|(b, _)| *b == (bu, bv)).map_or(Block::Surface, |(_, k)| *k)
    }
}

/// Centre lines and derived sizes shared by the layout check and the panels.
struct Layout {
    l1: f64,
    w: f64,
    h: f64,
    l2: f64,
    hb: f64,
    x2: f64,
    tan_tilt: f64,
    window: f64,
    bedroom_window: f64,
    skylight: f64,
    door: f64,
    door_y: f64,
}

impl Layout {
    fn new(spec: &SceneSpec, p: &Parameters) -> Self {
        let r = &spec.rooms;
        let [l1, w, h] = r.living;
        let [l2, _, hb] = r.bedroom;
        Self {
            l1,
            w,
            h,
            l2,
            hb,
            x2: l1 + r.wall_thickness,
            tan_tilt: p[3].to_radians().tan(),
            window: p[0],
            bedroom_window: p[0] * r.bedroom_window_ratio,
            skylight: p[1],
            door: p[2],
            door_y: 0.65 * w,
        }
    }

    /// Living ceiling height at `y`.
    fn ceiling(&self, y: f64) -> f64 {
        self.h + y * self.tan_tilt
    }
}

/// Checks that every opening fits its wall at parameters `p`; names the parameter.
pub(crate) fn check_layout(spec: &SceneSpec, p: &Parameters) -> Result<(), (&'static str, String)> {
    let l = Layout::new(spec, p);
    let fits = |size: f64, centre: f64, lo: f64, hi: f64| {
        size > 0.0 && centre - size / 2.0 >= lo + OPENING_MARGIN && centre + size / 2.0 <= hi - OPENING_MARGIN
    };
    if !fits(l.window, l.l1 / 2.0, 0.0, l.l1) || !fits(l.bedroom_window, l.l2 / 2.0, 0.0, l.l2) {
        return Err((PARAMETERS[0], format!("a window of width {} does not fit its wall", l.window)));
    }
    if !fits(l.skylight, l.l1 / 2.0, 0.0, l.l1) || !fits(l.skylight, l.w / 2.0, 0.0, l.w) {
        return Err((PARAMETERS[1], format!("a skylight of size {} does not fit the ceiling", l.skylight)));
    }
    if !fits(l.door, l.door_y, 0.0, l.w) {
        return Err((PARAMETERS[2], format!("a door of width {} does not fit the wall", l.door)));
    }
    if !(0.0..=45.0).contains(&p[3]) {
        return Err((PARAMETERS[3], format!("a tilt of {}° is outside 0° to 45°", p[3])));
    }
    let [cube1, cube2, bed, headboard] = furniture(&l);
    let inside = |(lo, hi): (DVec3, DVec3), x0: f64, x1: f64, z1: f64| {
        lo.x >= x0 + FURNITURE_GAP / 2.0
            && hi.x <= x1 - FURNITURE_GAP / 2.0
            && lo.y > 0.0
            && hi.y < l.w
            && hi.z < z1
    };
    let fits_living = inside(cube1, 0.0, l.l1, l.h) && inside(cube2, 0.0, l.l1, l.h);
    let fits_bedroom = inside(bed, l.x2, l.x2 + l.l2, l.hb) && inside(headboard, l.x2, l.x2 + l.l2, l.hb);
    if !(fits_living && fits_bedroom) {
        return Err(("rooms", "the rooms are too small for the furniture".into()));
    }
    Ok(())
}

/// The solids standing in the rooms at parameters `p` — the two cubes, the bed and its
/// headboard — as boxes (min, max corners): no face of the scene lies inside one.
pub fn solids(spec: &SceneSpec, p: &Parameters) -> Vec<(DVec3, DVec3)> {
    furniture(&Layout::new(spec, p)).to_vec()
}

/// Boxes (min, max corners) of the two cubes, the bed and its headboard.
fn furniture(l: &Layout) -> [(DVec3, DVec3); 4] {
    let cube = |cx: f64, cy: f64, sx: f64, sy: f64, sz: f64| {
        (DVec3::new(cx - sx / 2.0, cy - sy / 2.0, 0.0), DVec3::new(cx + sx / 2.0, cy + sy / 2.0, sz))
    };
    let bed_x = l.x2 + 0.5 * l.l2;
    let north = l.w - FURNITURE_GAP;
    [
        cube(0.3 * l.l1, 0.7 * l.w, 0.6, 0.6, 0.6),
        cube(0.62 * l.l1, 0.3 * l.w, 0.8, 0.8, 0.45),
        (DVec3::new(bed_x - 0.8, north - 0.1 - 2.0, 0.0), DVec3::new(bed_x + 0.8, north - 0.1, 0.5)),
        (DVec3::new(bed_x - 0.8, north - 0.1, 0.0), DVec3::new(bed_x + 0.8, north, 1.0)),
    ]
}

/// The five visible sides of a box standing on the floor (no bottom), lit outwards;
/// `omit_north` leaves out the +y side (where the bed touches its headboard).
fn box_panels<'a>(
    part: &'static str,
    albedo: [f64; 3],
    (lo, hi): (DVec3, DVec3),
    omit_north: bool,
) -> Vec<Panel<'a>> {
    let panel = |u: [f64; 2], v: [f64; 2], inward: DVec3, map: Box<dyn Fn(f64, f64) -> DVec3 + 'a>| Panel {
        part,
        albedo,
        u: u.to_vec(),
        v: v.to_vec(),
        special: Vec::new(),
        map,
        inward,
    };
    let mut p = vec![
        panel([lo.x, hi.x], [lo.y, hi.y], DVec3::Z, Box::new(move |u, v| DVec3::new(u, v, hi.z))),
        panel([lo.x, hi.x], [lo.z, hi.z], -DVec3::Y, Box::new(move |u, v| DVec3::new(u, lo.y, v))),
        panel([lo.y, hi.y], [lo.z, hi.z], -DVec3::X, Box::new(move |u, v| DVec3::new(lo.x, u, v))),
        panel([lo.y, hi.y], [lo.z, hi.z], DVec3::X, Box::new(move |u, v| DVec3::new(hi.x, u, v))),
    ];
    if !omit_north {
        p.push(panel([lo.x, hi.x], [lo.z, hi.z], DVec3::Y, Box::new(move |u, v| DVec3::new(u, hi.y, v))));
    }
    p
}

/// Every panel of the scene at parameters `p`, in a fixed order.
fn panels<'a>(spec: &'a SceneSpec, l: &'a Layout) -> Vec<Panel<'a>> {
    let m = &spec.materials;
    let r = &spec.rooms;
    let (sill, top) = (r.window_sill, r.window_sill + r.window_height);
    let dh = r.door_height;
    let (dy0, dy1) = (l.door_y - l.door / 2.0, l.door_y + l.door / 2.0);
    let centred = |lo: f64, hi: f64, size: f64| vec![lo, (lo + hi - size) / 2.0, (lo + hi + size) / 2.0, hi];
    let plain = |part, albedo, u: [f64; 2], v: [f64; 2], inward, map: Box<dyn Fn(f64, f64) -> DVec3 + 'a>| {
        Panel { part, albedo, u: u.to_vec(), v: v.to_vec(), special: Vec::new(), map, inward }
    };
    let (l1, w, h, x2, l2, hb) = (l.l1, l.w, l.h, l.x2, l.l2, l.hb);
    // Heights on walls under the tilted ceiling: exact below `knee`, stretched above it to
    // the ceiling at `y` (so openings keep their shape).
    let stretch = move |v: f64, knee: f64, y: f64| {
        if v <= knee {
            v
        } else {
            knee + (v - knee) / (h - knee) * (l.ceiling(y) - knee)
        }
    };
    let [cube1, cube2, bed, headboard] = furniture(l);
    let mut out = vec![
        floor("living floor", m.living_floor, [0.0, l1], w, &[cube1, cube2]),
        Panel {
            part: "living ceiling",
            albedo: m.living_ceiling,
            u: centred(0.0, l1, l.skylight),
            v: centred(0.0, w, l.skylight),
            special: vec![((1, 1), Block::Opening(FaceKind::Skylight, "skylight"))],
            map: Box::new(|u, v| DVec3::new(u, v, l.ceiling(v))),
            inward: -DVec3::Z,
        },
        Panel {
            part: "living south wall",
            albedo: m.living_walls,
            u: centred(0.0, l1, l.window),
            v: vec![0.0, sill, top, h],
            special: vec![((1, 1), Block::Opening(FaceKind::Window, "living window"))],
            map: Box::new(|u, v| DVec3::new(u, 0.0, v)),
            inward: DVec3::Y,
        },
        plain(
            "living north wall",
            m.living_walls,
            [0.0, l1],
            [0.0, h],
            -DVec3::Y,
            Box::new(move |u, v| DVec3::new(u, w, stretch(v, 0.0, w))),
        ),
        plain(
            "living west wall",
            m.living_walls,
            [0.0, w],
            [0.0, h],
            DVec3::X,
            Box::new(move |u, v| DVec3::new(0.0, u, stretch(v, 0.0, u))),
        ),
        Panel {
            part: "living door wall",
            albedo: m.living_walls,
            u: vec![0.0, dy0, dy1, w],
            v: vec![0.0, dh, h],
            special: vec![((1, 0), Block::Omitted)],
            map: Box::new(move |u, v| DVec3::new(l1, u, stretch(v, dh, u))),
            inward: -DVec3::X,
        },
        plain(
            "door frame",
            m.door_frame,
            [l1, x2],
            [0.0, dh],
            DVec3::Y,
            Box::new(move |u, v| DVec3::new(u, dy0, v)),
        ),
        plain(
            "door frame",
            m.door_frame,
            [l1, x2],
            [0.0, dh],
            -DVec3::Y,
            Box::new(move |u, v| DVec3::new(u, dy1, v)),
        ),
        plain(
            "door frame",
            m.door_frame,
            [l1, x2],
            [dy0, dy1],
            -DVec3::Z,
            Box::new(move |u, v| DVec3::new(u, v, dh)),
        ),
        plain(
            "door frame",
            m.door_frame,
            [l1, x2],
            [dy0, dy1],
            DVec3::Z,
            Box::new(move |u, v| DVec3::new(u, v, 0.0)),
        ),
        Panel {
            part: "bedroom door wall",
            albedo: m.bedroom_walls,
            u: vec![0.0, dy0, dy1, w],
            v: vec![0.0, dh, hb],
            special: vec![((1, 0), Block::Omitted)],
            map: Box::new(move |u, v| DVec3::new(x2, u, v)),
            inward: DVec3::X,
        },
        floor("bedroom floor", m.bedroom_floor, [x2, x2 + l2], w, &[bed, headboard]),
        plain(
            "bedroom ceiling",
            m.bedroom_ceiling,
            [x2, x2 + l2],
            [0.0, w],
            -DVec3::Z,
            Box::new(move |u, v| DVec3::new(u, v, hb)),
        ),
        Panel {
            part: "bedroom south wall",
            albedo: m.bedroom_walls,
            u: centred(x2, x2 + l2, l.bedroom_window),
            v: vec![0.0, sill, top, hb],
            special: vec![((1, 1), Block::Opening(FaceKind::Window, "bedroom window"))],
            map: Box::new(|u, v| DVec3::new(u, 0.0, v)),
            inward: DVec3::Y,
        },
        plain(
            "bedroom north wall",
            m.bedroom_walls,
            [x2, x2 + l2],
            [0.0, hb],
            -DVec3::Y,
            Box::new(move |u, v| DVec3::new(u, w, v)),
        ),
        plain(
            "bedroom east wall",
            m.bedroom_walls,
            [0.0, w],
            [0.0, hb],
            -DVec3::X,
            Box::new(move |u, v| DVec3::new(x2 + l2, u, v)),
        ),
    ];
    out.extend(box_panels("cube", m.furniture, cube1, false));
    out.extend(box_panels("cube", m.furniture, cube2, false));
    out.extend(box_panels("bed", m.bed, bed, true));
    let mut head = box_panels("bed", m.bed, headboard, false);
    // The headboard's south side below the bed's top lies against the bed: left out.
    for side in head.iter_mut().filter(|p| p.inward == -DVec3::Y) {
        side.v = vec![headboard.0.z, bed.1.z, headboard.1.z];
        side.special = vec![((0, 0), Block::Omitted)];
    }
    out.extend(head);
    out
}

/// A floor x ∈ `x`, y ∈ [0, `w`] with the footprints of the furniture standing on it left out
/// (their edges are breakpoints; the blocks under a box are omitted), so no floor face lies
/// inside a solid and the floor with the boxes' sides and tops stays a closed surface.
fn floor<'a>(
    part: &'static str,
    albedo: [f64; 3],
    x: [f64; 2],
    w: f64,
    boxes: &[(DVec3, DVec3)],
) -> Panel<'a> {
    let breakpoints = |ends: [f64; 2], inner: Vec<f64>| {
        let mut b: Vec<f64> = ends.into_iter().chain(inner).collect();
        b.sort_by(f64::total_cmp);
        b.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
        b
    };
    let u = breakpoints(x, boxes.iter().flat_map(|(lo, hi)| [lo.x, hi.x]).collect());
    let v = breakpoints([0.0, w], boxes.iter().flat_map(|(lo, hi)| [lo.y, hi.y]).collect());
    let mut special = Vec::new();
    for bu in 0..u.len() - 1 {
        for bv in 0..v.len() - 1 {
            let c = DVec3::new(0.5 * (u[bu] + u[bu + 1]), 0.5 * (v[bv] + v[bv + 1]), 0.0);
            if boxes.iter().any(|(lo, hi)| c.x > lo.x && c.x < hi.x && c.y > lo.y && c.y < hi.y) {
                special.push(((bu, bv), Block::Omitted));
            }
        }
    }
    Panel { part, albedo, u, v, special, map: Box::new(|u, v| DVec3::new(u, v, 0.0)), inward: DVec3::Z }
}

/// Cells per block of every panel: from the block's length at the default parameters.
fn cell_counts(spec: &SceneSpec) -> Vec<(Vec<usize>, Vec<usize>)> {
    let defaults = spec.defaults();
    let l = Layout::new(spec, &defaults);
    let cell = spec.resolution.cell;
    let count = |b: &[f64]| b.windows(2).map(|w| ((w[1] - w[0]) / cell).round().max(1.0) as usize).collect();
    let counts = panels(spec, &l).iter().map(|p| (count(&p.u), count(&p.v))).collect();
    counts
}

/// The scene's mesh at parameters `p` (checked against the ranges): the same triangles for
/// every `p`, only the vertex positions move.
pub fn build(spec: &SceneSpec, p: &Parameters) -> Result<SceneMesh, RadiosityError> {
    if let Err((name, message)) = check_layout(spec, p) {
        return Err(RadiosityError::Parameter { name: name.to_string(), message });
    }
    let l = Layout::new(spec, p);
    let panels = panels(spec, &l);
    let counts = cell_counts(spec);
    let mut mesh = SceneMesh {
        vertices: Vec::new(),
        faces: Vec::new(),
        albedo: Vec::new(),
        kind: Vec::new(),
        part: Vec::new(),
        part_names: Vec::new(),
    };
    let mut part_index: HashMap<&str, u16> = HashMap::new();
    let mut part_id = |name: &'static str, names: &mut Vec<String>| {
        *part_index.entry(name).or_insert_with(|| {
            names.push(name.to_string());
            (names.len() - 1) as u16
        })
    };
    for (panel, (nu, nv)) in panels.iter().zip(&counts) {
        let grid = |b: &[f64], n: &[usize]| {
            let mut g = Vec::new();
            for (k, w) in b.windows(2).enumerate() {
                g.extend((0..n[k]).map(|a| w[0] + (w[1] - w[0]) * a as f64 / n[k] as f64));
            }
            g.push(b[b.len() - 1]);
            g
        };
        let (us, vs) = (grid(&panel.u, nu), grid(&panel.v, nv));
        let (uc, vc) = ((us[0] + us[us.len() - 1]) / 2.0, (vs[0] + vs[vs.len() - 1]) / 2.0);
        let e = 1e-4 * (us[us.len() - 1] - us[0]).max(vs[vs.len() - 1] - vs[0]);
        let du = (panel.map)(uc + e, vc) - (panel.map)(uc - e, vc);
        let dv = (panel.map)(uc, vc + e) - (panel.map)(uc, vc - e);
        let flip = du.cross(dv).dot(panel.inward) < 0.0;
        let mut index: HashMap<(usize, usize), u32> = HashMap::new();
        let mut vertex = |i: usize, j: usize, vertices: &mut Vec<DVec3>| {
            *index.entry((i, j)).or_insert_with(|| {
                vertices.push((panel.map)(us[i], vs[j]));
                (vertices.len() - 1) as u32
            })
        };
        let mut i0 = 0;
        for (bu, &cu) in nu.iter().enumerate() {
            let mut j0 = 0;
            for (bv, &cv) in nv.iter().enumerate() {
                let block = panel.block(bu, bv);
                if block != Block::Omitted {
                    let (kind, part, albedo) = match block {
                        Block::Opening(kind, name) => (kind, name, [0.0; 3]),
                        _ => (FaceKind::Surface, panel.part, panel.albedo),
                    };
                    let id = part_id(part, &mut mesh.part_names);
                    for i in i0..i0 + cu {
                        for j in j0..j0 + cv {
                            let q = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)]
                                .map(|(a, b)| vertex(a, b, &mut mesh.vertices));
                            let tris = if flip {
                                [[q[0], q[2], q[1]], [q[0], q[3], q[2]]]
                            } else {
                                [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
                            };
                            for t in tris {
                                mesh.faces.push(t);
                                mesh.albedo.push(albedo);
                                mesh.kind.push(kind);
                                mesh.part.push(id);
                            }
                        }
                    }
                }
                j0 += cv;
            }
            i0 += cu;
        }
    }
    mesh.validate()?;
    Ok(mesh)
}
