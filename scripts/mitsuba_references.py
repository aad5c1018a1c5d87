#!/usr/bin/env python3
"""Writes the small test scenes of render/tests/mitsuba_reference.rs and their references.

For each scene, writes `render/tests/scenes/mitsuba/<name>.xml` and renders it with the
`mitsuba` Python package (3.9.1, variant scalar_rgb), the scene's integrator wrapped in
Mitsuba's `moment` integrator, which records per pixel the mean of the samples and of
their squares. Writes `<name>.mean.exr` (R, G, B: the reference image) and
`<name>.var.exr` (the variance of one sample, E[x^2] - E[x]^2, per CIE XYZ channel, which
is what Mitsuba's own render test divides by), both in Mitsuba's format for its render
tests: converted from XYZ to linear sRGB with the matrix below (the variance file is thus
XYZ variance stored through that linear map; the test maps it back).

Usage: scripts/mitsuba_references.py [--spp N] [names...]   (default: every scene, 32768 spp)
"""

import argparse
import os
import re
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "..", "render", "tests", "scenes", "mitsuba")

SIZE = 32

# Linear sRGB (Rec. 709 primaries, D65) to CIE XYZ, as Mitsuba's Bitmap converts; the Rust
# test uses the same matrix to bring both files back to XYZ, where the test is done.
SRGB_TO_XYZ = np.array(
    [
        [0.412453, 0.357580, 0.180423],
        [0.212671, 0.715160, 0.072169],
        [0.019334, 0.119193, 0.950227],
    ]
)
XYZ_TO_SRGB = np.linalg.inv(SRGB_TO_XYZ)

# An open-fronted box 2 x 2 x 2 (floor y=0, ceiling y=2, back wall z=-1, red left and green
# right walls) with a white cube, seen from the front. Rectangles face the inside.
BOX = """
    <bsdf type="diffuse" id="white"><rgb name="reflectance" value="0.7, 0.7, 0.7"/></bsdf>
    <bsdf type="diffuse" id="red"><rgb name="reflectance" value="0.6, 0.1, 0.1"/></bsdf>
    <bsdf type="diffuse" id="green"><rgb name="reflectance" value="0.1, 0.6, 0.15"/></bsdf>
    <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/></transform><ref id="white"/></shape>
    <shape type="rectangle"><transform name="to_world"><translate y="1" z="-1"/></transform><ref id="white"/></shape>
    <shape type="rectangle"><transform name="to_world"><rotate y="1" angle="90"/><translate x="-1" y="1"/></transform><ref id="red"/></shape>
    <shape type="rectangle"><transform name="to_world"><rotate y="1" angle="-90"/><translate x="1" y="1"/></transform><ref id="green"/></shape>
    <shape type="cube"><transform name="to_world"><scale value="0.3"/><rotate y="1" angle="25"/><translate x="0.35" y="0.3" z="-0.3"/></transform><ref id="white"/></shape>
"""
CEILING = """
    <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="90"/><translate y="2"/></transform><ref id="white"/></shape>
"""
AREA_LIGHT = """
    <shape type="rectangle">
        <transform name="to_world"><scale value="0.3"/><rotate x="1" angle="90"/><translate y="1.98"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf>
        <emitter type="area"><rgb name="radiance" value="12, 11, 9"/></emitter>
    </shape>
"""


# The blend scenes' sphere (a blend of diffuse red and rough gold, its weight to follow) and
# the start of their cube's blend (its weight and BSDFs to follow).
BLEND_SPHERE = """<shape type="sphere">
        <point name="center" value="-0.4, 0.4, 0.1"/><float name="radius" value="0.35"/>
        <bsdf type="blendbsdf">
"""
BLEND_CUBE = """            <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.2, 0.2"/></bsdf>
            <bsdf type="roughconductor"><string name="distribution" value="ggx"/><float name="alpha" value="0.2"/><string name="material" value="Au"/></bsdf>
        </bsdf>
    </shape>
    <shape type="cube">
        <transform name="to_world"><scale value="0.25"/><rotate y="1" angle="30"/><translate x="0.45" y="0.6" z="-0.3"/></transform>
        <bsdf type="blendbsdf">
"""


LOOK_AT_BOX = '<transform name="to_world"><lookat origin="0, 1, 3.4" target="0, 1, 0" up="0, 1, 0"/></transform>'
SQUARE_FILM = f'<integer name="width" value="{SIZE}"/><integer name="height" value="{SIZE}"/>'


BOX_FILTER = '<rfilter type="box"/>'


def sensor(plugin, params, film=SQUARE_FILM, rfilter=BOX_FILTER):
    """A `plugin` sensor with `params` (lines, to_world included), 64 independent samples per
    pixel and an hdrfilm sized by the `film` lines, filtered by `rfilter` (None: no rfilter
    element, Mitsuba's default gaussian)."""
    params = "\n        ".join(params)
    film = [film] if isinstance(film, str) else list(film)
    if rfilter is not None:
        film.append(rfilter)
    film = "\n            ".join(film)
    return f"""<sensor type="{plugin}">
        {params}
        <sampler type="independent"><integer name="sample_count" value="64"/></sampler>
        <film type="hdrfilm">
            {film}
        </film>
    </sensor>"""


PERSPECTIVE = sensor("perspective", ['<float name="fov" value="45"/>', LOOK_AT_BOX])


def scene(integrator, body, camera=PERSPECTIVE, box=True):
    """A scene of `body` (in the open box unless `box` is false) seen by `camera`."""
    return f"""<scene version="3.0.0">
    <integrator type="path">{integrator}</integrator>
    {camera}
{BOX if box else ""}{body}
</scene>
"""


def write_png(path):
    """A 16 x 12 8-bit sRGB PNG (written here with zlib, no imaging library): colour stripes
    with a diagonal, so that orientation, filtering and wrapping all show."""
    import struct
    import zlib

    w, h = 16, 12
    rows = b""
    for y in range(h):
        row = bytearray([0])  # filter type: none
        for x in range(w):
            r = 230 if (x // 4) % 2 == 0 else 40
            g = 200 if y < h // 2 else 60
            b = 220 if x == y else 30 + 10 * x
            row += bytes([r, g, b])
        rows += bytes(row)

    def chunk(kind, data):
        c = struct.pack(">I", len(data)) + kind + data
        return c + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    png = b"\x89PNG\r\n\x1a\n"
    png += chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(rows))
    png += chunk(b"IEND", b"")
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb") as f:
        f.write(png)


def write_png_pixels(path, w, h, pixel, grey=False):
    """An 8-bit PNG (no imaging library) of `w` x `h` pixels, `pixel(x, y)` giving values in
    [0, 1]: one (grey) or three (RGB) of them."""
    import struct
    import zlib

    rows = b""
    for y in range(h):
        row = bytearray([0])  # filter type: none
        for x in range(w):
            v = pixel(x, y)
            v = [v] if grey else list(v)
            row += bytes(int(round(255 * min(max(c, 0.0), 1.0))) for c in v)
        rows += bytes(row)

    def chunk(kind, data):
        c = struct.pack(">I", len(data)) + kind + data
        return c + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    png = b"\x89PNG\r\n\x1a\n"
    png += chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0 if grey else 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(rows))
    png += chunk(b"IEND", b"")
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb") as f:
        f.write(png)


def write_normal_map(path):
    """A 32 x 32 tangent-space normal map (RGB = (n + 1) / 2) of waves along u and v."""

    def normal(x, y):
        n = np.array([0.6 * np.cos(2 * np.pi * x / 8), 0.6 * np.sin(2 * np.pi * y / 8), 1.0])
        n /= np.linalg.norm(n)
        return (n + 1) / 2

    write_png_pixels(path, 32, 32, normal)


def write_height_map(path):
    """A 32 x 32 grey height field of bumps, for `bumpmap`."""
    write_png_pixels(
        path,
        32,
        32,
        lambda x, y: 0.5 + 0.5 * np.sin(2 * np.pi * x / 16) * np.cos(2 * np.pi * y / 16),
        grey=True,
    )


def write_sky_exr(path):
    """A 48 x 24 latitude-longitude OpenEXR sky: a blue-to-white gradient above the horizon, a
    brown ground below it, and a small bright sun (2 x 2 texels, radiance 60) 30 degrees up,
    so that importance sampling of the map matters."""
    import mitsuba as mi

    w, h = 48, 24
    img = np.zeros((h, w, 3), dtype=np.float32)
    for y in range(h):
        t = y / (h - 1)  # colatitude / pi
        if t < 0.5:
            img[y, :] = (0.3 + 1.0 * t, 0.5 + 0.8 * t, 1.2 - 0.4 * t)
        else:
            img[y, :] = (0.25, 0.18, 0.1)
        img[y, :, 0] *= 1.0 + 0.3 * np.sin(np.arange(w) * 2 * np.pi / w)
    img[7:9, 30:32] = (60.0, 55.0, 45.0)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    mi.Bitmap(img, mi.Bitmap.PixelFormat.RGB).write(path)


def write_colored_ply(path):
    """An ASCII PLY with float vertex colours (r, g, b): a 5 x 5 grid quad in z = 0 spanning
    [-1, 1]^2 whose colours run red to green across and blue up, and an octahedron of radius
    0.35 above it at z = 0.5 with one colour per vertex."""
    verts, faces = [], []
    n = 5
    for j in range(n):
        for i in range(n):
            x, y = -1 + 2 * i / (n - 1), -1 + 2 * j / (n - 1)
            verts.append((x, y, 0.0, 0.9 * (1 - i / (n - 1)), 0.9 * i / (n - 1), 0.8 * j / (n - 1)))
    for j in range(n - 1):
        for i in range(n - 1):
            a = j * n + i
            faces += [(a, a + 1, a + n + 1), (a, a + n + 1, a + n)]
    base = len(verts)
    octa = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
    cols = [(0.9, 0.1, 0.1), (0.1, 0.9, 0.1), (0.1, 0.1, 0.9), (0.9, 0.9, 0.1), (0.9, 0.1, 0.9), (0.1, 0.9, 0.9)]
    for (x, y, z), c in zip(octa, cols):
        verts.append((0.35 * x, 0.35 * y, 0.5 + 0.35 * z) + c)
    for f in [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]:
        faces.append(tuple(base + k for k in f))
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        f.write("ply\nformat ascii 1.0\n")
        f.write(f"element vertex {len(verts)}\n")
        for p in ("x", "y", "z", "r", "g", "b"):
            f.write(f"property float {p}\n")
        f.write(f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")
        for v in verts:
            f.write(" ".join(f"{c:.6f}" for c in v) + "\n")
        for t in faces:
            f.write("3 " + " ".join(str(k) for k in t) + "\n")


def write_attributes_ply(path):
    """An ASCII PLY of a 4 x 4 grid of squares in z = 0 spanning [-1, 1]^2, each two
    triangles with the same face values (Mitsuba reads triangles only), with Mitsuba mesh
    attributes besides positions: per vertex `weight_x` (one
    channel: `vertex_weight`) and `tint_r`, `tint_g`, `tint_b` (`vertex_tint_color`); per face
    `red`, `green`, `blue` (`face_color`) and `opacity_x` (`face_opacity`)."""
    n = 5
    verts, faces = [], []
    for j in range(n):
        for i in range(n):
            u, v = i / (n - 1), j / (n - 1)
            verts.append((-1 + 2 * u, -1 + 2 * v, 0.0, u * v, 0.2 + 0.7 * v, 0.8 * u, 0.9 - 0.6 * u))
    for j in range(n - 1):
        for i in range(n - 1):
            a = j * n + i
            k = j * (n - 1) + i
            colour = ((0.9, 0.2, 0.1), (0.1, 0.7, 0.3), (0.2, 0.3, 0.9), (0.8, 0.8, 0.2))[(i + j) % 4]
            opacity = (1.0, 0.25, 0.6, 0.0)[(k * 7 // 3) % 4]
            faces.append(((a, a + 1, a + n + 1), colour + (opacity,)))
            faces.append(((a, a + n + 1, a + n), colour + (opacity,)))
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        f.write("ply\nformat ascii 1.0\n")
        f.write(f"element vertex {len(verts)}\n")
        for p in ("x", "y", "z", "weight_x", "tint_r", "tint_g", "tint_b"):
            f.write(f"property float {p}\n")
        f.write(f"element face {len(faces)}\nproperty list uchar int vertex_indices\n")
        for p in ("red", "green", "blue", "opacity_x"):
            f.write(f"property float {p}\n")
        f.write("end_header\n")
        for v in verts:
            f.write(" ".join(f"{c:.6f}" for c in v) + "\n")
        for tri, values in faces:
            f.write("3 " + " ".join(str(k) for k in tri) + " " + " ".join(f"{c:.6f}" for c in values) + "\n")


def write_textured_obj(path):
    """A unit quad in z = 0 (two triangles) with texture coordinates running 0..2 in u and
    0..1 in v, so that Mitsuba's flip of an OBJ's v and the repeat wrap both show."""
    with open(path, "w") as f:
        f.write("v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n")
        f.write("vt 0 0\nvt 2 0\nvt 2 1\nvt 0 1\n")
        f.write("f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n")


def write_serialized(path):
    """A two-shape Mitsuba `.serialized` file (format 0x041C, version 4), written here so that
    the reader is checked against Mitsuba's: shape 0 an octahedron with vertex normals, single
    precision; shape 1 a slab (a flattened cube), double precision, no normals."""
    import struct
    import zlib

    def shape(name, v, f, normals=None, double=False):
        flags = (0x2000 if double else 0x1000) | (0x0001 if normals is not None else 0)
        real = "<f8" if double else "<f4"
        body = struct.pack("<I", flags) + name.encode() + b"\0"
        body += struct.pack("<QQ", len(v), len(f))
        body += np.asarray(v, real).tobytes()
        if normals is not None:
            body += np.asarray(normals, real).tobytes()
        body += np.asarray(f, "<u4").tobytes()
        return struct.pack("<HH", 0x041C, 4) + zlib.compress(body)

    octa = [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]]
    octa_faces = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]
    slab = [[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    # Outward-facing (counter-clockwise seen from outside) faces of the cube x, y, z in {-1, 1}.
    slab_faces = [
        [0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5],  # x = -1, x = +1
        [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6],  # y = -1, y = +1
        [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3],  # z = -1, z = +1
    ]
    data, offsets = b"", []
    for blob in (shape("octahedron", octa, octa_faces, normals=octa), shape("slab", slab, slab_faces, double=True)):
        offsets.append(len(data))
        data += blob
    data += b"".join(struct.pack("<Q", o) for o in offsets) + struct.pack("<I", len(offsets))
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb") as f:
        f.write(data)


SCENES = {
    # The area light and diffuse surfaces every other test builds on.
    "area": scene("", CEILING + AREA_LIGHT),
    # Only what the camera sees directly: the light.
    "max_depth_1": scene('<integer name="max_depth" value="1"/>', CEILING + AREA_LIGHT),
    # Direct illumination only.
    "max_depth_2": scene('<integer name="max_depth" value="2"/>', CEILING + AREA_LIGHT),
    # Camera rays pass through the light and do not see the sky behind the open front.
    "hide_emitters": scene(
        '<boolean name="hide_emitters" value="true"/>',
        CEILING
        + AREA_LIGHT
        + '<emitter type="constant"><rgb name="radiance" value="0.4, 0.5, 0.6"/></emitter>',
    ),
    "point": scene(
        "",
        CEILING
        + '<emitter type="point"><point name="position" value="-0.2, 1.5, 0.1"/>'
        + '<rgb name="intensity" value="3, 2.5, 2"/></emitter>',
    ),
    "spot": scene(
        "",
        CEILING
        + """<emitter type="spot">
        <transform name="to_world"><lookat origin="-0.3, 1.9, 0.4" target="0.2, 0, -0.3" up="0, 0, 1"/></transform>
        <rgb name="intensity" value="8, 7, 6"/>
        <float name="cutoff_angle" value="35"/><float name="beam_width" value="20"/>
    </emitter>""",
    ),
    # A shapegroup (a cube coloured by a sampled spectrum, on a small slab) placed by two
    # instances, one scaled and turned.
    "instances": scene(
        "",
        CEILING
        + AREA_LIGHT
        + """<shape type="shapegroup" id="group">
        <shape type="cube">
            <transform name="to_world"><scale value="0.15"/><translate y="0.15"/></transform>
            <bsdf type="diffuse"><spectrum name="reflectance" value="400:0.1, 480:0.2, 560:0.8, 640:0.5, 700:0.3"/></bsdf>
        </shape>
        <shape type="cube">
            <transform name="to_world"><scale x="0.25" y="0.02" z="0.25"/><translate y="0.02"/></transform>
        </shape>
    </shape>
    <shape type="instance"><ref id="group"/>
        <transform name="to_world"><translate x="-0.5" z="0.2"/></transform></shape>
    <shape type="instance"><ref id="group"/>
        <transform name="to_world"><scale value="1.5"/><rotate y="1" angle="30"/><translate x="-0.3" y="0.9" z="-0.7"/></transform></shape>""",
    ),
    # An orthographic camera, its view sized by the scale before the lookat, seeing the box
    # (and its open front's sky) from slightly above.
    "orthographic": scene(
        "",
        CEILING
        + AREA_LIGHT
        + '<emitter type="constant"><rgb name="radiance" value="0.2, 0.25, 0.3"/></emitter>',
        camera=sensor(
            "orthographic",
            [
                '<transform name="to_world"><scale x="1.25" y="1.25"/><lookat origin="0.3, 1.6, 3.4" target="0, 0.9, 0" up="0, 1, 0"/></transform>'
            ],
        ),
    ),
    # A thin lens focused on the white cube, with an aperture wide enough to blur the
    # back wall and the light.
    "thinlens": scene(
        "",
        CEILING + AREA_LIGHT,
        camera=sensor(
            "thinlens",
            [
                '<float name="fov" value="45"/>',
                '<float name="aperture_radius" value="0.12"/>',
                '<float name="focus_distance" value="3.7"/>',
                LOOK_AT_BOX,
            ],
        ),
    ),
    # Plastic: a cube with Mitsuba's defaults but its colour, and a nonlinear slab of
    # another index on the floor, lit by the area light and a sky.
    "plastic": scene(
        "",
        CEILING
        + AREA_LIGHT
        + '<emitter type="constant"><rgb name="radiance" value="0.15, 0.15, 0.2"/></emitter>'
        + """<shape type="cube">
        <transform name="to_world"><scale value="0.25"/><rotate y="1" angle="-20"/><translate x="-0.4" y="0.25" z="0.1"/></transform>
        <bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.1, 0.3, 0.6"/></bsdf>
    </shape>
    <shape type="cube">
        <transform name="to_world"><scale x="0.5" y="0.01" z="0.4"/><translate y="0.01" z="0.45"/></transform>
        <bsdf type="plastic">
            <rgb name="diffuse_reflectance" value="0.7, 0.2, 0.1"/>
            <float name="int_ior" value="1.9"/>
            <boolean name="nonlinear" value="true"/>
        </bsdf>
    </shape>""",
    ),
    # Rough plastic: Mitsuba's defaults (Beckmann, alpha 0.1) on a sphere with a colour, a
    # rough GGX nonlinear cube of another index, and a textured GGX slab (a checkerboard as
    # the diffuse reflectance), lit by the area light and a sky.
    "roughplastic": scene(
        "",
        CEILING
        + AREA_LIGHT
        + '<emitter type="constant"><rgb name="radiance" value="0.15, 0.15, 0.2"/></emitter>'
        + """<shape type="sphere">
        <point name="center" value="-0.45, 0.35, 0.1"/><float name="radius" value="0.33"/>
        <bsdf type="roughplastic"><rgb name="diffuse_reflectance" value="0.1, 0.3, 0.6"/></bsdf>
    </shape>
    <shape type="cube">
        <transform name="to_world"><scale value="0.25"/><rotate y="1" angle="30"/><translate x="0.45" y="0.6" z="-0.3"/></transform>
        <bsdf type="roughplastic">
            <string name="distribution" value="ggx"/><float name="alpha" value="0.3"/>
            <rgb name="diffuse_reflectance" value="0.7, 0.2, 0.1"/>
            <float name="int_ior" value="1.7"/>
            <boolean name="nonlinear" value="true"/>
        </bsdf>
    </shape>
    <shape type="cube">
        <transform name="to_world"><scale x="0.5" y="0.01" z="0.4"/><translate y="0.01" z="0.45"/></transform>
        <bsdf type="roughplastic">
            <string name="distribution" value="ggx"/><float name="alpha" value="0.15"/>
            <texture type="checkerboard" name="diffuse_reflectance">
                <rgb name="color0" value="0.8, 0.8, 0.2"/><rgb name="color1" value="0.1, 0.2, 0.5"/>
                <transform name="to_uv"><scale value="4"/></transform>
            </texture>
        </bsdf>
    </shape>""",
    ),
    # Rough glass: a GGX sphere (Mitsuba's default BK7 in air), a rougher GGX slab of another
    # index with tinted transmittance, lit by the area light and a sky. (GGX only: Cohort
    # samples Beckmann's normals by D(m) cos, unbiased but noisier through glass than
    # Mitsuba's visible-normal sampling, which this variance-sensitive test notices.)
    "roughdielectric": scene(
        "",
        CEILING
        + AREA_LIGHT
        + '<emitter type="constant"><rgb name="radiance" value="0.15, 0.15, 0.2"/></emitter>'
        + """<shape type="sphere">
        <point name="center" value="-0.35, 0.4, 0.1"/><float name="radius" value="0.35"/>
        <bsdf type="roughdielectric"><string name="distribution" value="ggx"/><float name="alpha" value="0.2"/></bsdf>
    </shape>
    <shape type="cube">
        <transform name="to_world"><scale x="0.3" y="0.3" z="0.05"/><rotate y="1" angle="-25"/><translate x="0.45" y="0.6" z="0.1"/></transform>
        <bsdf type="roughdielectric">
            <string name="distribution" value="ggx"/><float name="alpha" value="0.4"/>
            <float name="int_ior" value="1.33"/>
            <rgb name="specular_transmittance" value="0.9, 0.6, 0.3"/>
        </bsdf>
    </shape>""",
    ),
    # Anisotropic rough glass: a GGX slab and a Beckmann cube, their roughness different along
    # and across dp/du (the cube's faces turned so that it shows), and a Beckmann slab whose
    # alpha_u is a texture. Caustics through the glass leave a few pixel channels beyond
    # chance (0 to 5 over seeds 1 to 9, 7 allowed). Open sheets: `dielectric_sheets`.
    "roughdielectric_anisotropic": scene(
        "",
        CEILING
        + AREA_LIGHT
        + '<emitter type="constant"><rgb name="radiance" value="0.15, 0.15, 0.2"/></emitter>'
        + """<shape type="cube">
        <transform name="to_world"><scale x="0.3" y="0.3" z="0.05"/><rotate y="1" angle="-25"/><translate x="0.45" y="0.6" z="0.1"/></transform>
        <bsdf type="roughdielectric">
            <string name="distribution" value="ggx"/><float name="alpha_u" value="0.05"/><float name="alpha_v" value="0.45"/>
            <rgb name="specular_transmittance" value="0.9, 0.6, 0.3"/>
        </bsdf>
    </shape>
    <shape type="cube">
        <transform name="to_world"><scale value="0.22"/><rotate y="1" angle="35"/><rotate x="1" angle="20"/><translate x="-0.4" y="0.35" z="0.0"/></transform>
        <bsdf type="roughdielectric">
            <string name="distribution" value="beckmann"/><float name="alpha_u" value="0.4"/><float name="alpha_v" value="0.06"/>
            <float name="int_ior" value="1.33"/>
        </bsdf>
    </shape>
    <shape type="cube">
        <transform name="to_world"><scale x="0.25" y="0.15" z="0.04"/><rotate x="1" angle="60"/><translate x="0.0" y="0.8" z="-0.7"/></transform>
        <bsdf type="roughdielectric">
            <string name="distribution" value="beckmann"/>
            <texture type="bitmap" name="alpha_u"><string name="filename" value="textures/stripes.png"/></texture>
            <float name="alpha_v" value="0.1"/>
        </bsdf>
    </shape>""",
    ),
    # Blends: diffuse and rough gold on a sphere (weight 0.3), and on the cube a diffuse
    # blended (0.6) with a blend of rough aluminium and a rough plastic (nested second).
    # (Delta lobes in blends: `blendbsdf_delta`.)
    "blendbsdf": scene(
        "",
        CEILING
        + AREA_LIGHT
        + BLEND_SPHERE
        + """            <float name="weight" value="0.3"/>
"""
        + BLEND_CUBE
        + """            <float name="weight" value="0.6"/>
            <bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.6, 0.3"/></bsdf>
            <bsdf type="blendbsdf">
                <float name="weight" value="0.5"/>
                <bsdf type="roughconductor"><float name="alpha" value="0.3"/><string name="material" value="Al"/></bsdf>
                <bsdf type="roughplastic"><string name="distribution" value="ggx"/><rgb name="diffuse_reflectance" value="0.1, 0.2, 0.7"/></bsdf>
            </bsdf>
        </bsdf>
    </shape>""",
    ),
    # Textured blend weights: a bitmap's luminance on a sphere (diffuse and rough gold), a
    # checkerboard (read as a number, with Mitsuba's eval_1 quirk) on the cube.
    "blendbsdf_texture": scene(
        "",
        CEILING
        + AREA_LIGHT
        + BLEND_SPHERE
        + """            <texture type="bitmap" name="weight"><string name="filename" value="textures/stripes.png"/></texture>
"""
        + BLEND_CUBE
        + """            <texture type="checkerboard" name="weight"><rgb name="color0" value="0.9"/><rgb name="color1" value="0.1"/>
                <transform name="to_uv"><scale x="3" y="3"/></transform></texture>
            <bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.6, 0.3"/></bsdf>
            <bsdf type="roughplastic"><string name="distribution" value="ggx"/><rgb name="diffuse_reflectance" value="0.1, 0.2, 0.7"/></bsdf>
        </bsdf>
    </shape>""",
    ),
    # A 32 x 32 crop window of a 64 x 48 film: the field of view and aspect are the film's.
    "crop": scene(
        "",
        CEILING + AREA_LIGHT,
        camera=sensor(
            "perspective",
            ['<float name="fov" value="50"/>', LOOK_AT_BOX],
            film=[
                '<integer name="width" value="64"/><integer name="height" value="48"/>',
                '<integer name="crop_offset_x" value="22"/><integer name="crop_offset_y" value="4"/>',
                '<integer name="crop_width" value="32"/><integer name="crop_height" value="32"/>',
            ],
        ),
    ),
    # Both shapes of a .serialized file (meshes/shapes.serialized, see write_serialized): an
    # octahedron shaded with its vertex normals and a double-precision slab under it, shaded
    # with the normals Mitsuba recomputes for a mesh without any.
    "serialized": scene(
        "",
        CEILING
        + AREA_LIGHT
        + """<shape type="serialized">
        <string name="filename" value="meshes/shapes.serialized"/>
        <transform name="to_world"><scale value="0.3"/><translate x="-0.4" y="0.5" z="0.1"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.5, 0.7"/></bsdf>
    </shape>
    <shape type="serialized">
        <string name="filename" value="meshes/shapes.serialized"/>
        <integer name="shape_index" value="1"/>
        <transform name="to_world"><scale x="0.4" y="0.1" z="0.4"/><translate x="-0.4" y="0.1" z="0.1"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.6, 0.2"/></bsdf>
    </shape>""",
    ),
    # Mitsuba's analytic sphere, cylinder and disk, which the renderer tessellates and shades
    # with interpolated normals.
    "analytic_shapes": scene(
        "",
        CEILING
        + AREA_LIGHT
        + """<shape type="sphere">
        <point name="center" value="-0.45, 0.35, 0.2"/><float name="radius" value="0.3"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.4, 0.8"/></bsdf>
    </shape>
    <shape type="cylinder">
        <point name="p0" value="0.5, 0.0, 0.45"/><point name="p1" value="0.5, 0.6, 0.45"/>
        <float name="radius" value="0.15"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.5, 0.2"/></bsdf>
    </shape>
    <shape type="disk">
        <transform name="to_world"><scale value="0.15"/><rotate x="1" angle="-90"/><translate x="0.5" y="0.6" z="0.45"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.5, 0.2"/></bsdf>
    </shape>""",
    ),
    # Reconstruction filters: Mitsuba's default (a film without rfilter: gaussian, stddev 0.5)
    # and a wide tent sampled beyond the film's edges. (Filters with negative lobes cannot be
    # judged this way: where the splatting weights change sign, what the `moment` integrator
    # records is no variance; kernels/tests/film_filter.rs checks them exactly.)
    "filter_gaussian": scene(
        "",
        CEILING + AREA_LIGHT,
        camera=sensor("perspective", ['<float name="fov" value="45"/>', LOOK_AT_BOX], rfilter=None),
    ),
    "filter_tent_border": scene(
        "",
        CEILING + AREA_LIGHT,
        camera=sensor(
            "perspective",
            ['<float name="fov" value="45"/>', LOOK_AT_BOX],
            film=[SQUARE_FILM, '<boolean name="sample_border" value="true"/>'],
            rfilter='<rfilter type="tent"><float name="radius" value="1.25"/></rfilter>',
        ),
    ),
    # Conductors: a gold sphere by `material` name, and the cube given eta and k directly.
    "conductor": scene(
        "",
        CEILING
        + AREA_LIGHT
        + """<shape type="sphere">
        <point name="center" value="-0.4, 0.4, 0.1"/><float name="radius" value="0.35"/>
        <bsdf type="conductor"><string name="material" value="Au"/></bsdf>
    </shape>
    <shape type="cube">
        <transform name="to_world"><scale value="0.2"/><rotate y="1" angle="-30"/><translate x="0.45" y="0.8" z="-0.5"/></transform>
        <bsdf type="conductor">
            <rgb name="eta" value="0.2, 0.9, 1.2"/><rgb name="k" value="3.0, 2.5, 2.0"/>
            <rgb name="specular_reflectance" value="0.9, 0.9, 0.8"/>
        </bsdf>
    </shape>""",
    ),
    # Rough conductors: Mitsuba's default Beckmann distribution (copper), and GGX.
    "roughconductor": scene(
        "",
        CEILING
        + AREA_LIGHT
        + """<shape type="sphere">
        <point name="center" value="-0.4, 0.4, 0.1"/><float name="radius" value="0.35"/>
        <bsdf type="roughconductor"><string name="material" value="Cu"/><float name="alpha" value="0.2"/></bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" value="0.5, 0.95, -0.4"/><float name="radius" value="0.3"/>
        <bsdf type="roughconductor">
            <string name="distribution" value="ggx"/><float name="alpha" value="0.35"/>
            <string name="material" value="Al"/>
        </bsdf>
    </shape>""",
    ),
    # Anisotropic rough conductors: a GGX sphere stretched along dp/du, a Beckmann one whose
    # alpha_u and alpha_v are checkerboards (read as numbers), and an OBJ quad whose
    # alpha_u is a bitmap (its texture coordinates turn the anisotropy).
    "roughconductor_anisotropic": scene(
        "",
        CEILING
        + AREA_LIGHT
        + """<shape type="sphere">
        <point name="center" value="-0.4, 0.4, 0.1"/><float name="radius" value="0.35"/>
        <bsdf type="roughconductor"><string name="distribution" value="ggx"/><string name="material" value="Cu"/>
            <float name="alpha_u" value="0.4"/><float name="alpha_v" value="0.04"/></bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" value="0.5, 0.95, -0.4"/><float name="radius" value="0.3"/>
        <bsdf type="roughconductor"><string name="distribution" value="beckmann"/><string name="material" value="Al"/>
            <texture type="checkerboard" name="alpha_u"><float name="color0" value="0.05"/><float name="color1" value="0.4"/>
                <transform name="to_uv"><scale x="6" y="6"/></transform></texture>
            <texture type="checkerboard" name="alpha_v"><float name="color0" value="0.3"/><float name="color1" value="0.08"/>
                <transform name="to_uv"><scale x="6" y="6"/></transform></texture>
        </bsdf>
    </shape>
    <shape type="obj">
        <string name="filename" value="meshes/textured_quad.obj"/>
        <transform name="to_world"><scale value="0.5"/><rotate y="1" angle="20"/><translate x="0.1" y="1.3" z="-0.95"/></transform>
        <bsdf type="roughconductor"><string name="distribution" value="ggx"/><string name="material" value="Au"/>
            <texture type="bitmap" name="alpha_u"><string name="filename" value="textures/stripes.png"/></texture>
            <float name="alpha_v" value="0.05"/>
        </bsdf>
    </shape>""",
    ),
    # Textures: checkerboards on the rectangle (the floor, scaled by to_uv), on the cube's
    # faces and on a sphere; a PNG bitmap (textures/stripes.png, see write_png) on the back
    # wall (bilinear), on an OBJ quad with its own texture coordinates, and as a plastic's
    # diffuse reflectance on the cube (nearest, clamp).
    "checkerboard": scene(
        "",
        CEILING
        + AREA_LIGHT
        + """<shape type="rectangle">
        <transform name="to_world"><scale value="0.9"/><rotate x="1" angle="-90"/><translate y="0.01"/></transform>
        <bsdf type="diffuse"><texture type="checkerboard" name="reflectance">
            <rgb name="color0" value="0.8, 0.7, 0.2"/><rgb name="color1" value="0.1, 0.2, 0.6"/>
            <transform name="to_uv"><scale x="4" y="3"/><translate x="0.1"/></transform>
        </texture></bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" value="-0.45, 0.45, 0.1"/><float name="radius" value="0.3"/>
        <bsdf type="diffuse"><texture type="checkerboard" name="reflectance">
            <transform name="to_uv"><scale x="8" y="4"/></transform>
        </texture></bsdf>
    </shape>
    <shape type="cube">
        <transform name="to_world"><scale value="0.25"/><rotate y="1" angle="-35"/><rotate x="1" angle="20"/><translate x="0.45" y="0.95" z="-0.3"/></transform>
        <bsdf type="diffuse"><texture type="checkerboard" name="reflectance">
            <rgb name="color0" value="0.9, 0.3, 0.3"/><rgb name="color1" value="0.9, 0.9, 0.9"/>
            <transform name="to_uv"><scale value="3"/></transform>
        </texture></bsdf>
    </shape>""",
    ),
    "bitmap": scene(
        "",
        CEILING
        + AREA_LIGHT
        + """<texture type="bitmap" id="stripes"><string name="filename" value="textures/stripes.png"/></texture>
    <shape type="rectangle">
        <transform name="to_world"><scale value="0.8"/><translate y="1" z="-0.99"/></transform>
        <bsdf type="diffuse"><ref name="reflectance" id="stripes"/></bsdf>
    </shape>
    <shape type="obj">
        <string name="filename" value="meshes/textured_quad.obj"/>
        <transform name="to_world"><scale x="0.5" y="0.3"/><rotate y="1" angle="40"/><translate x="-0.5" y="0.5" z="0.1"/></transform>
        <bsdf type="twosided"><bsdf type="diffuse"><texture type="bitmap" name="reflectance">
            <string name="filename" value="textures/stripes.png"/>
        </texture></bsdf></bsdf>
    </shape>
    <shape type="cube">
        <transform name="to_world"><scale value="0.25"/><rotate y="1" angle="-30"/><translate x="0.45" y="0.25" z="0.1"/></transform>
        <bsdf type="plastic">
            <texture type="bitmap" name="diffuse_reflectance">
                <string name="filename" value="textures/stripes.png"/>
                <string name="filter_type" value="nearest"/><string name="wrap_mode" value="clamp"/>
                <transform name="to_uv"><scale value="1.5"/><translate x="-0.25" y="-0.25"/></transform>
            </texture>
        </bsdf>
    </shape>""",
    ),
    # Textured conductor reflectance: a checkerboard on a rough conductor sphere, the stripes
    # bitmap on a smooth gold cube.
    "conductor_texture": scene(
        "",
        CEILING
        + AREA_LIGHT
        + """<shape type="sphere">
        <point name="center" value="-0.4, 0.4, 0.1"/><float name="radius" value="0.35"/>
        <bsdf type="roughconductor"><string name="distribution" value="ggx"/><float name="alpha" value="0.25"/>
            <texture type="checkerboard" name="specular_reflectance">
                <rgb name="color0" value="0.9, 0.9, 0.9"/><rgb name="color1" value="0.2, 0.5, 0.9"/>
                <transform name="to_uv"><scale x="6" y="3"/></transform>
            </texture>
        </bsdf>
    </shape>
    <shape type="cube">
        <transform name="to_world"><scale value="0.25"/><rotate y="1" angle="-30"/><translate x="0.45" y="0.25" z="0.1"/></transform>
        <bsdf type="conductor"><string name="material" value="Au"/>
            <texture type="bitmap" name="specular_reflectance"><string name="filename" value="textures/stripes.png"/></texture>
        </bsdf>
    </shape>""",
    ),
    # Mitsuba `mask`: a half-transparent sheet under the light (light samples are blocked by
    # it, paths pass through it), and a checkerboard-cut panel in front of the back wall.
    "mask": scene(
        "",
        CEILING
        + AREA_LIGHT
        + """<shape type="rectangle">
        <transform name="to_world"><scale value="0.5"/><rotate x="1" angle="90"/><translate x="-0.2" y="1.5"/></transform>
        <bsdf type="mask">
            <float name="opacity" value="0.4"/>
            <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.5, 0.8"/></bsdf></bsdf>
        </bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale x="0.5" y="0.4"/><rotate y="1" angle="20"/><translate x="0.2" y="0.7" z="-0.4"/></transform>
        <bsdf type="mask">
            <texture type="checkerboard" name="opacity">
                <float name="color0" value="0.9"/><float name="color1" value="0.1"/>
                <transform name="to_uv"><scale value="3"/></transform>
            </texture>
            <bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.3, 0.1"/></bsdf>
        </bsdf>
    </shape>""",
    ),
    # No ceiling: sunlight falls into the box from above.
    # An open scene lit only by an OpenEXR environment map (textures/sky.exr, see
    # write_sky_exr), turned and scaled: a diffuse and a rough gold sphere on a ground, the sky
    # seen behind them.
    "envmap": scene(
        "",
        """<emitter type="envmap">
        <string name="filename" value="textures/sky.exr"/>
        <float name="scale" value="0.8"/>
        <transform name="to_world"><rotate y="1" angle="60"/></transform>
    </emitter>
    <shape type="rectangle">
        <transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" value="-0.5, 0.45, 0"/><float name="radius" value="0.45"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.3, 0.2"/></bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" value="0.55, 0.4, 0.2"/><float name="radius" value="0.4"/>
        <bsdf type="roughconductor"><string name="distribution" value="ggx"/><float name="alpha" value="0.15"/><string name="material" value="Au"/></bsdf>
    </shape>""",
        camera=sensor(
            "perspective",
            [
                '<float name="fov" value="50"/>',
                '<transform name="to_world"><lookat origin="0, 1.1, 3.2" target="0, 0.5, 0" up="0, 1, 0"/></transform>',
            ],
        ),
        box=False,
    ),
    # The box lit by a point light and, through its open front, by an 8-bit sRGB PNG as the
    # environment (textures/stripes.png), tilted: the light choice between the two, and
    # the decoding of the PNG.
    "envmap_png": scene(
        "",
        CEILING
        + '<emitter type="point"><point name="position" value="-0.2, 1.5, 0.1"/>'
        + '<rgb name="intensity" value="1.5, 1.2, 1"/></emitter>'
        + """<emitter type="envmap">
        <string name="filename" value="textures/stripes.png"/>
        <transform name="to_world"><rotate x="1" angle="30"/></transform>
    </emitter>""",
    ),
    # Normal maps (textures/waves_normal.png, see write_normal_map, raw): on a diffuse panel,
    # a rough gold sphere, and a two-sided panel seen from its back (flip_normals), under the
    # area light.
    "normalmap": scene(
        "",
        CEILING
        + AREA_LIGHT
        + """<texture type="bitmap" id="waves"><string name="filename" value="textures/waves_normal.png"/><boolean name="raw" value="true"/></texture>
    <shape type="rectangle">
        <transform name="to_world"><scale x="0.45" y="0.6"/><translate x="-0.45" y="0.8" z="-0.9"/></transform>
        <bsdf type="normalmap"><ref name="normalmap" id="waves"/><bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.6, 0.4"/></bsdf></bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" value="0.4, 1.3, -0.2"/><float name="radius" value="0.3"/>
        <bsdf type="normalmap"><ref name="normalmap" id="waves"/>
            <bsdf type="roughconductor"><string name="distribution" value="ggx"/><float name="alpha" value="0.2"/><string name="material" value="Au"/></bsdf>
        </bsdf>
    </shape>
    <shape type="rectangle">
        <boolean name="flip_normals" value="true"/>
        <transform name="to_world"><scale value="0.3"/><rotate x="1" angle="-30"/><translate x="-0.3" y="0.35" z="0.3"/></transform>
        <bsdf type="twosided"><bsdf type="normalmap"><ref name="normalmap" id="waves"/><bsdf type="diffuse"><rgb name="reflectance" value="0.3, 0.5, 0.7"/></bsdf></bsdf></bsdf>
    </shape>""",
    ),
    # Bump maps (textures/bumps_height.png, see write_height_map, raw) with their scale: on
    # a rough plastic panel and a diffuse sphere.
    "bumpmap": scene(
        "",
        CEILING
        + AREA_LIGHT
        + """<shape type="rectangle">
        <transform name="to_world"><scale x="0.5" y="0.6"/><translate x="-0.4" y="0.8" z="-0.9"/></transform>
        <bsdf type="bumpmap">
            <texture type="bitmap"><string name="filename" value="textures/bumps_height.png"/><boolean name="raw" value="true"/></texture>
            <float name="scale" value="0.1"/>
            <bsdf type="roughplastic"><string name="distribution" value="ggx"/><float name="alpha" value="0.15"/><rgb name="diffuse_reflectance" value="0.2, 0.4, 0.7"/></bsdf>
        </bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" value="-0.45, 0.35, 0.2"/><float name="radius" value="0.3"/>
        <bsdf type="bumpmap">
            <texture type="bitmap"><string name="filename" value="textures/bumps_height.png"/><boolean name="raw" value="true"/></texture>
            <float name="scale" value="0.05"/>
            <bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.5, 0.3"/></bsdf>
        </bsdf>
    </shape>""",
    ),
    # A projector throwing textures/stripes.png (16 x 12: its aspect shapes the beam) onto
    # the back wall and the cube, with a scale and a field of view along y.
    "projector": scene(
        "",
        CEILING
        + """<emitter type="projector">
        <transform name="to_world"><lookat origin="0.2, 1.5, 0.9" target="0, 0.8, -1" up="0, 1, 0"/></transform>
        <texture type="bitmap" name="irradiance"><string name="filename" value="textures/stripes.png"/></texture>
        <float name="scale" value="2.5"/>
        <float name="fov" value="30"/><string name="fov_axis" value="y"/>
    </emitter>""",
    ),
    # A spot whose beam is coloured by textures/stripes.png.
    "spot_texture": scene(
        "",
        CEILING
        + """<emitter type="spot">
        <transform name="to_world"><lookat origin="-0.2, 1.9, 0.3" target="0.1, 0, -0.5" up="0, 0, 1"/></transform>
        <rgb name="intensity" value="9, 8, 7"/>
        <float name="cutoff_angle" value="40"/><float name="beam_width" value="30"/>
        <texture type="bitmap" name="texture"><string name="filename" value="textures/stripes.png"/></texture>
    </emitter>""",
    ),
    # Vertex colours of a PLY (meshes/colored.ply, see write_colored_ply) through a
    # `mesh_attribute` texture with a scale, on a diffuse grid and octahedron.
    "vertex_colors": scene(
        "",
        CEILING
        + AREA_LIGHT
        + """<shape type="ply">
        <string name="filename" value="meshes/colored.ply"/>
        <transform name="to_world"><scale value="0.6"/><rotate x="1" angle="-20"/><translate y="0.8" z="-0.6"/></transform>
        <bsdf type="diffuse">
            <texture type="mesh_attribute" name="reflectance"><string name="name" value="vertex_color"/><float name="scale" value="0.9"/></texture>
        </bsdf>
    </shape>""",
    ),
    # Mesh attributes of a PLY (meshes/attributes.ply, see write_attributes_ply):
    # per-face colours blended with gold by a one-channel vertex attribute, and in front, a
    # smaller copy masked by a one-channel face attribute and coloured per vertex.
    "mesh_attributes": scene(
        "",
        CEILING
        + AREA_LIGHT
        + """<shape type="ply">
        <string name="filename" value="meshes/attributes.ply"/>
        <transform name="to_world"><scale value="0.7"/><rotate x="1" angle="-15"/><translate y="0.9" z="-0.7"/></transform>
        <bsdf type="blendbsdf">
            <texture type="mesh_attribute" name="weight"><string name="name" value="vertex_weight"/></texture>
            <bsdf type="diffuse"><texture type="mesh_attribute" name="reflectance"><string name="name" value="face_color"/></texture></bsdf>
            <bsdf type="roughconductor"><string name="distribution" value="ggx"/><float name="alpha" value="0.3"/><string name="material" value="Au"/></bsdf>
        </bsdf>
    </shape>
    <shape type="ply">
        <string name="filename" value="meshes/attributes.ply"/>
        <transform name="to_world"><scale value="0.3"/><rotate y="1" angle="35"/><translate x="-0.3" y="0.5" z="0.2"/></transform>
        <bsdf type="mask">
            <texture type="mesh_attribute" name="opacity"><string name="name" value="face_opacity"/></texture>
            <bsdf type="twosided"><bsdf type="diffuse"><texture type="mesh_attribute" name="reflectance"><string name="name" value="vertex_tint_color"/><float name="scale" value="0.9"/></texture></bsdf></bsdf>
        </bsdf>
    </shape>""",
    ),
    # Principled: a checkered sphere with every reflection lobe (metallic, tinted specular,
    # sheen, clearcoat, flatness) and an anisotropic metal-like cube whose `specular` sets eta.
    "principled": scene(
        "",
        CEILING
        + AREA_LIGHT
        + """<shape type="sphere">
        <point name="center" value="-0.4, 0.4, 0.1"/><float name="radius" value="0.35"/>
        <bsdf type="principled">
            <texture type="checkerboard" name="base_color">
                <rgb name="color0" value="0.8, 0.2, 0.1"/><rgb name="color1" value="0.2, 0.4, 0.8"/>
                <transform name="to_uv"><scale x="4" y="4"/></transform>
            </texture>
            <float name="roughness" value="0.4"/><float name="metallic" value="0.3"/>
            <float name="spec_tint" value="0.5"/><float name="sheen" value="0.6"/>
            <float name="sheen_tint" value="0.5"/><float name="clearcoat" value="0.7"/>
            <float name="clearcoat_gloss" value="0.4"/><float name="flatness" value="0.3"/>
        </bsdf>
    </shape>
    <shape type="cube">
        <transform name="to_world"><scale value="0.25"/><rotate y="1" angle="30"/><translate x="0.45" y="0.6" z="-0.3"/></transform>
        <bsdf type="principled">
            <rgb name="base_color" value="0.9, 0.7, 0.3"/>
            <float name="roughness" value="0.35"/><float name="anisotropic" value="0.7"/>
            <float name="metallic" value="0.8"/><float name="specular" value="0.7"/>
        </bsdf>
    </shape>""",
    ),
    # An area light with a textured radiance (textures/stripes.png on a rectangle on the
    # back wall) beside the usual ceiling light: seen directly and through light sampling
    # on the floor and the cube. (Texture coordinates in [0, 1]: Mitsuba samples such a
    # light through its texture and the shape's inverse parameterisation, which reaches
    # only the points whose coordinates lie in [0, 1]^2, so its image of a light with
    # coordinates beyond is too dark.)
    "area_texture": scene(
        "",
        CEILING
        + AREA_LIGHT
        + """<shape type="rectangle">
        <transform name="to_world"><scale x="0.6" y="0.35"/><translate x="-0.3" y="1.1" z="-0.98"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.2, 0.2"/></bsdf>
        <emitter type="area">
            <texture type="bitmap" name="radiance"><string name="filename" value="textures/stripes.png"/></texture>
        </emitter>
    </shape>""",
    ),
    # Principled numbers as textures (read as numbers per hit): a sphere whose roughness,
    # anisotropy, metallic, sheen and clearcoat are checkerboards, and a principledthin cube
    # whose specular and diffuse transmission are a bitmap's luminance and a checkerboard.
    "principled_textured": scene(
        "",
        CEILING
        + AREA_LIGHT
        + """<shape type="sphere">
        <point name="center" value="-0.4, 0.4, 0.1"/><float name="radius" value="0.35"/>
        <bsdf type="principled">
            <rgb name="base_color" value="0.2, 0.7, 0.3"/>
            <texture type="checkerboard" name="roughness"><float name="color0" value="0.35"/><float name="color1" value="0.7"/>
                <transform name="to_uv"><scale x="4" y="4"/></transform></texture>
            <texture type="checkerboard" name="anisotropic"><float name="color0" value="0.8"/><float name="color1" value="0.05"/>
                <transform name="to_uv"><scale x="6" y="6"/></transform></texture>
            <texture type="checkerboard" name="metallic"><float name="color0" value="0.7"/><float name="color1" value="0.1"/>
                <transform name="to_uv"><scale x="4" y="4"/></transform></texture>
            <texture type="checkerboard" name="sheen"><float name="color0" value="0.2"/><float name="color1" value="0.9"/>
                <transform name="to_uv"><scale x="3" y="3"/></transform></texture>
            <texture type="checkerboard" name="clearcoat"><float name="color0" value="0.9"/><float name="color1" value="0.1"/>
                <transform name="to_uv"><scale x="3" y="3"/></transform></texture>
            <float name="specular" value="0.7"/>
        </bsdf>
    </shape>
    <shape type="cube">
        <transform name="to_world"><scale value="0.25"/><rotate y="1" angle="30"/><translate x="0.45" y="0.6" z="-0.3"/></transform>
        <bsdf type="principledthin">
            <rgb name="base_color" value="0.9, 0.6, 0.3"/><float name="roughness" value="0.4"/>
            <texture type="bitmap" name="spec_trans"><string name="filename" value="textures/stripes.png"/></texture>
            <texture type="checkerboard" name="diff_trans"><float name="color0" value="0.2"/><float name="color1" value="1.5"/>
                <transform name="to_uv"><scale x="2" y="2"/></transform></texture>
        </bsdf>
    </shape>""",
    ),
    # Principled with specular transmission: a glassy sphere (eta given) and a half
    # transmitting, partly metallic cube (eta from `specular`): the back-side lobes too.
    "principled_glass": scene(
        "",
        CEILING
        + AREA_LIGHT
        + '<emitter type="constant"><rgb name="radiance" value="0.15, 0.15, 0.2"/></emitter>'
        + """<shape type="sphere">
        <point name="center" value="-0.35, 0.4, 0.1"/><float name="radius" value="0.35"/>
        <bsdf type="principled">
            <rgb name="base_color" value="0.9, 0.8, 0.6"/>
            <float name="spec_trans" value="0.85"/><float name="roughness" value="0.25"/>
            <float name="eta" value="1.4"/><float name="clearcoat" value="0.3"/>
        </bsdf>
    </shape>
    <shape type="cube">
        <transform name="to_world"><scale x="0.3" y="0.3" z="0.08"/><rotate y="1" angle="-25"/><translate x="0.45" y="0.6" z="0.1"/></transform>
        <bsdf type="principled">
            <rgb name="base_color" value="0.3, 0.7, 0.5"/>
            <float name="spec_trans" value="0.5"/><float name="metallic" value="0.2"/>
            <float name="roughness" value="0.5"/><float name="spec_tint" value="0.3"/>
        </bsdf>
    </shape>""",
    ),
    # Principledthin: a translucent leaf-like sheet (diffuse and specular transmission)
    # below the light, and a sphere with diffuse transmission. (Rough enough that the light
    # seen through the sheet is no caustic: with a sharp transmission lobe the image is so
    # heavy-tailed that Mitsuba's own renders fail this test at its budget now and then.)
    "principledthin": scene(
        "",
        CEILING
        + AREA_LIGHT
        + """<shape type="rectangle">
        <transform name="to_world"><scale x="0.45" y="0.3"/><rotate x="1" angle="-60"/><rotate y="1" angle="20"/><translate x="0.3" y="0.9" z="0.2"/></transform>
        <bsdf type="principledthin">
            <rgb name="base_color" value="0.3, 0.8, 0.2"/>
            <float name="spec_trans" value="0.4"/><float name="diff_trans" value="0.8"/>
            <float name="roughness" value="0.6"/><float name="eta" value="1.6"/>
            <float name="sheen" value="0.4"/><float name="spec_tint" value="0.5"/>
        </bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" value="-0.4, 0.4, 0.1"/><float name="radius" value="0.3"/>
        <bsdf type="principledthin">
            <rgb name="base_color" value="0.8, 0.5, 0.3"/>
            <float name="diff_trans" value="1.2"/><float name="flatness" value="0.5"/>
            <float name="roughness" value="0.6"/>
        </bsdf>
    </shape>""",
    ),
    # A blend of two diffuse BSDFs, weighted by a bitmap's luminance, lit only by a
    # directional light (so only light samples reach it) with direct illumination only:
    # Mitsuba evaluates a blend as its weighted sum, and a renderer that picks one BSDF per
    # light sample instead shows that choice as noise Mitsuba's image lacks.
    "blendbsdf_direct": scene(
        '<integer name="max_depth" value="2"/>',
        '<emitter type="directional"><vector name="direction" value="0.3, -1, -0.4"/>'
        + '<rgb name="irradiance" value="2, 1.8, 1.5"/></emitter>'
        + """<shape type="sphere">
        <point name="center" value="-0.1, 0.5, 0.0"/><float name="radius" value="0.45"/>
        <bsdf type="blendbsdf">
            <texture type="bitmap" name="weight"><string name="filename" value="textures/stripes.png"/></texture>
            <bsdf type="diffuse"><rgb name="reflectance" value="0, 0.5, 0.5"/></bsdf>
            <bsdf type="diffuse"><rgb name="reflectance" value="1, 1, 0"/></bsdf>
        </bsdf>
    </shape>""",
    ),
    # Blends with a delta lobe: diffuse and smooth gold on the sphere, a plastic (its
    # coating a delta reflection) and rough aluminium on a cube. Mitsuba weighs a delta
    # direction drawn in a blend by the blend's value over its density there
    # (`cohort_kernels::scatter`), which darkens the mirror part against the blend's
    # expectation; the image must be Mitsuba's. Lit by a sky through the open box: under
    # the small area light the mirrors' caustics left Mitsuba itself at 3066-3072 of 3072
    # channels against its own reference, too close to the limit for a test.
    "blendbsdf_delta": scene(
        "",
        '<emitter type="constant"><rgb name="radiance" value="0.9, 0.85, 0.8"/></emitter>'
        + BLEND_SPHERE
        + """            <float name="weight" value="0.4"/>
            <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.2, 0.2"/></bsdf>
            <bsdf type="conductor"><string name="material" value="Au"/></bsdf>
        </bsdf>
    </shape>
    <shape type="cube">
        <transform name="to_world"><scale value="0.25"/><rotate y="1" angle="30"/><translate x="0.45" y="0.6" z="-0.3"/></transform>
        <bsdf type="blendbsdf">
            <float name="weight" value="0.5"/>
            <bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.1, 0.2, 0.6"/></bsdf>
            <bsdf type="roughconductor"><string name="distribution" value="ggx"/><float name="alpha" value="0.2"/><string name="material" value="Al"/></bsdf>
        </bsdf>
    </shape>""",
    ),
    # Emitters of very different power together: a bright point light, the area light and
    # a dim, low spot whose patch on the floor it lights about as much as the others do.
    "uneven_emitters": scene(
        "",
        CEILING
        + AREA_LIGHT
        + '<emitter type="point"><point name="position" value="-0.7, 1.7, 0.5"/>'
        + '<rgb name="intensity" value="30, 27, 24"/></emitter>'
        + """<emitter type="spot">
        <transform name="to_world"><lookat origin="-0.4, 0.6, 0.5" target="-0.4, 0, 0.5" up="0, 0, 1"/></transform>
        <rgb name="intensity" value="1, 1.3, 1.8"/>
        <float name="cutoff_angle" value="20"/><float name="beam_width" value="15"/>
    </emitter>""",
    ),
    # Open glass sheets between the camera and the box: a smooth one seen from its front, a
    # rough one seen from its back and a principled one with full transmission. A camera ray
    # refracts once, so Mitsuba's radiance scale of a refraction (1 / eta² entering, eta²
    # leaving) shows in full; it cancels only over paths that enter glass and leave it.
    "dielectric_sheets": scene(
        "",
        CEILING
        + AREA_LIGHT
        + """<shape type="rectangle">
        <transform name="to_world"><scale x="0.3" y="0.45"/><rotate y="1" angle="20"/><translate x="-0.45" y="0.9" z="1.5"/></transform>
        <bsdf type="dielectric"/>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale x="0.3" y="0.45"/><rotate y="1" angle="160"/><translate x="0.2" y="1.1" z="1.5"/></transform>
        <bsdf type="roughdielectric"><string name="distribution" value="ggx"/><float name="alpha" value="0.25"/></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale x="0.2" y="0.3"/><rotate x="1" angle="-15"/><translate x="0.6" y="0.5" z="1.6"/></transform>
        <bsdf type="principled"><float name="spec_trans" value="1.0"/><float name="roughness" value="0.3"/><rgb name="base_color" value="0.9, 0.9, 0.9"/></bsdf>
    </shape>""",
    ),
    "directional": scene(
        "",
        '<emitter type="directional"><vector name="direction" value="0.3, -1, -0.4"/>'
        + '<rgb name="irradiance" value="2, 1.8, 1.5"/></emitter>',
    ),
}


def render(xml, spp):
    """The image and the per-sample variance of `xml` at `spp` samples per pixel."""
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    # The scene's own integrator, wrapped in `moment`; its sampler's count set to `spp`.
    wrapped = xml.replace('<integrator type="path">', '<integrator type="moment"><integrator type="path">', 1)
    wrapped = wrapped.replace("</integrator>", "</integrator></integrator>", 1)
    wrapped = re.sub(r'name="sample_count" value="\d+"', f'name="sample_count" value="{spp}"', wrapped)
    # File names in the scenes are relative to their folder, as when Cohort loads them.
    mi.Thread.thread().file_resolver().prepend(OUT)
    scene = mi.load_string(wrapped)
    img = np.array(mi.render(scene, seed=0), dtype=np.float64)
    # Channels: R, G, B, then the first and second moments of the wrapped integrator's
    # samples, which Mitsuba's `moment` integrator records in CIE XYZ.
    if img.shape[2] != 9:
        sys.exit(f"expected 9 film channels (RGB and two moments of XYZ), found {img.shape[2]}")
    rgb, m1, m2 = img[:, :, 0:3], img[:, :, 3:6], img[:, :, 6:9]
    if not np.allclose(rgb @ SRGB_TO_XYZ.T, m1, rtol=1e-3, atol=1e-5):
        sys.exit("the first moment is not the image in XYZ: channels are not in the expected order")
    var_xyz = np.maximum(m2 - m1 * m1, 0.0)
    # Stored as Mitsuba's render tests store them: both images converted from XYZ to RGB.
    return m1 @ XYZ_TO_SRGB.T, var_xyz @ XYZ_TO_SRGB.T


def write_exr(path, rgb):
    import mitsuba as mi

    bmp = mi.Bitmap(np.ascontiguousarray(rgb.astype(np.float32)), mi.Bitmap.PixelFormat.RGB)
    bmp.write(path)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--spp", type=int, default=32768)
    ap.add_argument("names", nargs="*")
    a = ap.parse_args()
    names = a.names or list(SCENES)
    os.makedirs(OUT, exist_ok=True)
    write_serialized(os.path.join(OUT, "meshes", "shapes.serialized"))
    write_textured_obj(os.path.join(OUT, "meshes", "textured_quad.obj"))
    write_colored_ply(os.path.join(OUT, "meshes", "colored.ply"))
    write_attributes_ply(os.path.join(OUT, "meshes", "attributes.ply"))
    write_png(os.path.join(OUT, "textures", "stripes.png"))
    write_sky_exr(os.path.join(OUT, "textures", "sky.exr"))
    write_normal_map(os.path.join(OUT, "textures", "waves_normal.png"))
    write_height_map(os.path.join(OUT, "textures", "bumps_height.png"))
    for name in names:
        xml = SCENES[name]
        with open(os.path.join(OUT, f"{name}.xml"), "w") as f:
            f.write(xml)
        mean, var = render(xml, a.spp)
        write_exr(os.path.join(OUT, f"{name}.mean.exr"), mean)
        write_exr(os.path.join(OUT, f"{name}.var.exr"), var)
        print(f"{name}: mean {mean.mean(axis=(0, 1))}, per-sample variance {var.mean(axis=(0, 1))}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
