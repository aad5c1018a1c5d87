//! Procedural triangle meshes in object space: Mitsuba's analytic shapes (`rectangle`, `cube`,
//! tessellated `sphere`) for the XML loader, and the building blocks (cylinders, lathes, tori,
//! arches, grids) the embedded scene generators assemble. All are closed or one-sided surfaces with
//! counter-clockwise = outward/front winding, because diffuse surfaces are one-sided and a wrongly
//! wound wall renders black.

use std::collections::HashMap;
use std::f32::consts::{PI, TAU};

use glam::{Vec2, Vec3};

use crate::mesh::TriMesh;

impl TriMesh {
    pub fn push_vertex(&mut self, p: Vec3) -> u32 {
        self.positions.push(p);
        (self.positions.len() - 1) as u32
    }

    pub fn push_triangle(&mut self, a: u32, b: u32, c: u32) {
        self.indices.push([a, b, c]);
    }

    /// Quad `a b c d` in counter-clockwise order, split along `a c`.
    pub fn push_quad(&mut self, a: u32, b: u32, c: u32, d: u32) {
        self.indices.push([a, b, c]);
        self.indices.push([a, c, d]);
    }
}

/// Mitsuba `rectangle`: [-1,1]^2 in the z = 0 plane, normal +z, 2 triangles; texture
/// coordinates ((x + 1) / 2, (y + 1) / 2), as Mitsuba's.
pub fn rectangle() -> TriMesh {
    let mut m = grid(1, 1);
    m.uvs = Some(
        m.positions
            .iter()
            .map(|p| Vec2::new(0.5 * p.x + 0.5, 0.5 * p.y + 0.5))
            .collect(),
    );
    m
}

/// [-1,1]^2 in z = 0, normal +z, cut into `nx` x `ny` quads (2 triangles each).
pub fn grid(nx: u32, ny: u32) -> TriMesh {
    let mut m = TriMesh::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let x = -1.0 + 2.0 * i as f32 / nx as f32;
            let y = -1.0 + 2.0 * j as f32 / ny as f32;
            m.push_vertex(Vec3::new(x, y, 0.0));
        }
    }
    let row = nx + 1;
    for j in 0..ny {
        for i in 0..nx {
            let a = j * row + i;
            m.push_quad(a, a + 1, a + row + 1, a + row);
        }
    }
    m
}

/// Each cube face as (outward normal, two in-plane axes); the axes get ordered so that u x v = n.
const CUBE_FACES: [(Vec3, Vec3, Vec3); 6] = [
    (Vec3::X, Vec3::Y, Vec3::Z),
    (Vec3::NEG_X, Vec3::Z, Vec3::Y),
    (Vec3::Y, Vec3::Z, Vec3::X),
    (Vec3::NEG_Y, Vec3::X, Vec3::Z),
    (Vec3::Z, Vec3::X, Vec3::Y),
    (Vec3::NEG_Z, Vec3::Y, Vec3::X),
];

/// Mitsuba `cube`: [-1,1]^3, outward normals, 12 triangles (4 own vertices per face, so face
/// normals stay sharp even if shaded smooth).
pub fn cube() -> TriMesh {
    let mut m = TriMesh::new();
    for (n, u, v) in CUBE_FACES {
        // Make (u, v, n) right-handed so that u x v = n: then (-u-v, u-v, u+v, -u+v) is CCW seen
        // from outside.
        let v = if u.cross(v).dot(n) > 0.0 { v } else { -v };
        let a = m.push_vertex(n - u - v);
        let b = m.push_vertex(n + u - v);
        let c = m.push_vertex(n + u + v);
        let d = m.push_vertex(n - u + v);
        m.push_quad(a, b, c, d);
    }
    m.uvs = Some(
        m.positions
            .chunks(4)
            .zip(CUBE_FACES)
            .flat_map(|(face, (n, _, _))| face.iter().map(move |&p| cube_uv(n, p)))
            .collect(),
    );
    m
}

/// Texture coordinates of point `p` on the face of Mitsuba's cube with outward normal `n`
/// (its mesh's, read back from the `mitsuba` package with ray queries).
fn cube_uv(n: Vec3, p: Vec3) -> Vec2 {
    let h = |x: f32| 0.5 * x + 0.5;
    let (u, v) = if n == Vec3::Z {
        (h(p.y), h(p.x))
    } else if n == Vec3::NEG_Z {
        (h(-p.y), h(p.x))
    } else if n == Vec3::X {
        (h(p.y), h(-p.z))
    } else if n == Vec3::NEG_X {
        (h(p.y), h(p.z))
    } else if n == Vec3::Y {
        (h(-p.x), h(-p.z))
    } else {
        (h(p.z), h(p.x))
    };
    Vec2::new(u, v)
}

/// [-1,1]^3 with every face cut into `n` x `n` quads: 12 n^2 triangles, outward.
pub fn subdivided_cube(n: u32) -> TriMesh {
    let mut m = TriMesh::new();
    let face = grid(n, n);
    for (normal, u, v) in CUBE_FACES {
        let v = if u.cross(v).dot(normal) > 0.0 { v } else { -v };
        let base = m.positions.len() as u32;
        m.positions
            .extend(face.positions.iter().map(|p| normal + p.x * u + p.y * v));
        m.indices
            .extend(face.indices.iter().map(|t| t.map(|i| i + base)));
    }
    m
}

/// Box of half extents `half` with edges and corners rounded to `radius`, from a
/// [`subdivided_cube`] of `n`: 12 n^2 triangles. Used for cushions, table tops, capitals.
pub fn rounded_box(half: Vec3, radius: f32, n: u32) -> TriMesh {
    let inner = (half - Vec3::splat(radius)).max(Vec3::ZERO);
    let mut m = subdivided_cube(n);
    for p in &mut m.positions {
        let q = *p * half;
        let c = q.clamp(-inner, inner);
        *p = c + (q - c).normalize_or_zero() * radius;
    }
    m
}

/// Axis-aligned box between `lo` and `hi`, outward normals, 12 triangles.
pub fn aabb_box(lo: Vec3, hi: Vec3) -> TriMesh {
    let c = 0.5 * (lo + hi);
    let h = 0.5 * (hi - lo);
    let mut m = cube();
    for p in &mut m.positions {
        *p = c + *p * h;
    }
    m
}

/// Subdivision level of the tessellated Mitsuba `sphere`: an icosphere of level 4 has 5,120
/// triangles (the density of the reference scenes' `sphere_5120.obj`) and deviates from the true
/// sphere by at most 0.2 % of the radius; vertices lie ON the sphere, so the mesh is inscribed.
pub const SPHERE_SUBDIVISIONS: u32 = 4;

/// Unit icosphere: 20 * 4^level triangles, vertex normals = positions (smooth shading of the
/// analytic sphere it stands for).
pub fn icosphere(level: u32) -> TriMesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut positions: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, positions: &mut Vec<Vec3>| -> u32 {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                positions.push(((positions[a as usize] + positions[b as usize]) * 0.5).normalize());
                (positions.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(faces.len() * 4);
        for [a, b, c] in faces {
            let ab = midpoint(a, b, &mut positions);
            let bc = midpoint(b, c, &mut positions);
            let ca = midpoint(c, a, &mut positions);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        faces = next;
    }
    TriMesh {
        normals: Some(positions.clone()),
        uvs: None,
        attributes: Vec::new(),
        positions,
        indices: faces,
    }
}

/// Surface of revolution about +y. `profile` is a list of (radius, height) points; the surface faces
/// outward when the profile runs upward on the outside (bottom to top). `segments` around. A point
/// with radius 0 becomes a pole (one vertex, triangle fan), so closed solids need no caps.
pub fn lathe(profile: &[Vec2], segments: u32) -> TriMesh {
    lathe_with(profile, segments, |_| 1.0)
}

/// [`lathe`] with the radius multiplied by `1 - depth * (0.5 + 0.5 cos(flutes * phi))`: the
/// vertical grooves of a classical column shaft.
pub fn fluted_lathe(profile: &[Vec2], segments: u32, flutes: u32, depth: f32) -> TriMesh {
    lathe_with(profile, segments, |phi| {
        1.0 - depth * (0.5 + 0.5 * (flutes as f32 * phi).cos())
    })
}

fn lathe_with(profile: &[Vec2], segments: u32, radial: impl Fn(f32) -> f32) -> TriMesh {
    let mut m = TriMesh::new();
    let mut rings: Vec<Vec<u32>> = Vec::with_capacity(profile.len());
    for p in profile {
        if p.x == 0.0 {
            rings.push(vec![m.push_vertex(Vec3::new(0.0, p.y, 0.0))]);
        } else {
            rings.push(
                (0..segments)
                    .map(|s| {
                        let phi = TAU * s as f32 / segments as f32;
                        let r = p.x * radial(phi);
                        m.push_vertex(Vec3::new(r * phi.cos(), p.y, -r * phi.sin()))
                    })
                    .collect(),
            );
        }
    }
    for w in rings.windows(2) {
        let (lo, hi) = (&w[0], &w[1]);
        for s in 0..segments as usize {
            let s1 = (s + 1) % segments as usize;
            match (lo.len(), hi.len()) {
                (1, 1) => {}
                (1, _) => m.push_triangle(lo[0], hi[s1], hi[s]),
                (_, 1) => m.push_triangle(lo[s], lo[s1], hi[0]),
                _ => m.push_quad(lo[s], lo[s1], hi[s1], hi[s]),
            }
        }
    }
    m
}

/// Closed cylinder of radius 1 from y = 0 to y = 1, `segments` around, `rings` bands along the
/// height, flat caps. 2 * segments * (rings + 1) triangles.
pub fn cylinder(segments: u32, rings: u32) -> TriMesh {
    let mut profile = vec![Vec2::new(0.0, 0.0)];
    profile.extend((0..=rings).map(|r| Vec2::new(1.0, r as f32 / rings as f32)));
    profile.push(Vec2::new(0.0, 1.0));
    lathe(&profile, segments)
}

/// Closed cone, base radius 1 at y = 0, apex at y = 1. 2 * segments triangles.
pub fn cone(segments: u32) -> TriMesh {
    lathe(
        &[
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 1.0),
        ],
        segments,
    )
}

/// Torus with the ring in the xy plane (axis z), like the reference scene's `torus.obj`: major radius
/// `major`, tube radius `minor`, `nu` segments around the ring, `nv` around the tube.
/// 2 * nu * nv triangles, smooth normals.
pub fn torus(major: f32, minor: f32, nu: u32, nv: u32) -> TriMesh {
    let mut m = TriMesh::new();
    let mut normals = Vec::new();
    for i in 0..nu {
        let u = TAU * i as f32 / nu as f32;
        let dir = Vec3::new(u.cos(), u.sin(), 0.0);
        for j in 0..nv {
            let v = TAU * j as f32 / nv as f32;
            let n = dir * v.cos() + Vec3::Z * v.sin();
            m.push_vertex(dir * major + n * minor);
            normals.push(n);
        }
    }
    for i in 0..nu {
        for j in 0..nv {
            let a = i * nv + j;
            let b = ((i + 1) % nu) * nv + j;
            let c = ((i + 1) % nu) * nv + (j + 1) % nv;
            let d = i * nv + (j + 1) % nv;
            m.push_quad(a, b, c, d);
        }
    }
    m.normals = Some(normals);
    m
}

/// A wall panel with a round-arched opening, the repeating element of an arcade. The panel spans
/// x in [-half_width, half_width], y in [0, height], z in [-depth/2, depth/2]; the opening is a half
/// disc of `radius` (< half_width, < height) centred at the origin, so piers below y = 0 are separate
/// geometry. Front (+z) and back (-z) faces and the curved soffit facing into the opening;
/// 6 * (segments + 2) triangles. The sides and top are left open: neighbouring panels and the
/// floor slab above cover them.
pub fn arch_panel(half_width: f32, radius: f32, height: f32, depth: f32, segments: u32) -> TriMesh {
    // Angles of the arc samples, plus the two rectangle corners so that the region between arc and
    // outer boundary stays star-shaped from the centre and can be cut into quads.
    let corner = height.atan2(half_width);
    let mut angles: Vec<f32> = (0..=segments)
        .map(|i| PI * i as f32 / segments as f32)
        .collect();
    angles.push(corner);
    angles.push(PI - corner);
    angles.sort_by(f32::total_cmp);
    let outer = |a: f32| -> Vec2 {
        let d = Vec2::new(a.cos(), a.sin());
        // Distance along d to the rectangle boundary x = +-half_width or y = height.
        let tx = if d.x.abs() > 1e-6 {
            half_width / d.x.abs()
        } else {
            f32::INFINITY
        };
        let ty = if d.y > 1e-6 {
            height / d.y
        } else {
            f32::INFINITY
        };
        d * tx.min(ty)
    };
    let hz = 0.5 * depth;
    let mut m = TriMesh::new();
    let n = angles.len() as u32;
    for z in [hz, -hz] {
        for &a in &angles {
            m.push_vertex(Vec3::new(radius * a.cos(), radius * a.sin(), z));
            let o = outer(a);
            m.push_vertex(Vec3::new(o.x, o.y, z));
        }
    }
    let front = 0;
    let back = 2 * n;
    for i in 0..n - 1 {
        let (a0, o0, a1, o1) = (2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3);
        // Angles increase counter-clockwise seen from +z.
        m.push_quad(front + a0, front + o0, front + o1, front + a1);
        m.push_quad(back + a0, back + a1, back + o1, back + o0);
        // Soffit: faces the arc centre.
        m.push_quad(front + a0, front + a1, back + a1, back + a0);
    }
    m
}
