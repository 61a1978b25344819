#!/usr/bin/env python3
"""Writes the hand-made glTF seeds of the fuzz corpora and the glTF findings kept as regressions.

    python3 fuzz/make_seeds.py        (from the repository root; rewrites the files it names)

The seeds reach what the campaigns' own queues did not: images in buffer views and by URI,
samplers, texture transforms, sparse accessors (with and without a base view), morph targets,
skins, animations, several scenes, strips and fans, interleaved and normalized attributes. The
findings are the inputs that made cadr or the glTF crate panic or abort before they were
refused (see fuzz/README.md). Standard library only, deterministic output.
"""

import base64
import json
import os
import struct
import zlib

ROOT = os.path.dirname(os.path.abspath(__file__))


def png(width, height, rgba):
    """A PNG of 8-bit RGBA texels (a list of 4-tuples, row by row)."""

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    rows = b"".join(
        b"\x00" + bytes(c for texel in rgba[y * width:(y + 1) * width] for c in texel)
        for y in range(height)
    )
    header = struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
            + chunk(b"IDAT", zlib.compress(rows, 9)) + chunk(b"IEND", b""))


CHECKER = png(2, 2, [(255, 255, 255, 255), (0, 0, 0, 255), (0, 0, 0, 255), (255, 255, 255, 128)])


class Buffer:
    """One binary buffer built view by view (each view 4-byte aligned)."""

    def __init__(self):
        self.data = bytearray()
        self.views = []

    def view(self, data, stride=None, target=None):
        while len(self.data) % 4:
            self.data.append(0)
        view = {"buffer": 0, "byteOffset": len(self.data), "byteLength": len(data)}
        if stride is not None:
            view["byteStride"] = stride
        if target is not None:
            view["target"] = target
        self.data += data
        self.views.append(view)
        return len(self.views) - 1


def floats(values):
    return struct.pack("<%df" % len(values), *values)


QUAD_POSITIONS = [0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0]
QUAD_NORMALS = [0, 0, 1] * 4
QUAD_UVS = [0, 1, 1, 1, 1, 0, 0, 0]
QUAD_MIN_MAX = {"min": [0, 0, 0], "max": [1, 1, 0]}


def vec3(view, count, **extra):
    accessor = {"bufferView": view, "componentType": 5126, "count": count, "type": "VEC3"}
    accessor.update(extra)
    return accessor


def document(buffer, uri=True, **members):
    doc = {"asset": {"version": "2.0", "generator": "cadr fuzz/make_seeds.py"}}
    buffer_json = {"byteLength": len(buffer.data)}
    if uri:
        buffer_json["uri"] = ("data:application/octet-stream;base64,"
                              + base64.b64encode(bytes(buffer.data)).decode())
    doc["buffers"] = [buffer_json]
    doc["bufferViews"] = buffer.views
    doc.update(members)
    return doc


def glb(doc, buffer):
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    binary = bytes(buffer.data) + b"\x00" * (-len(buffer.data) % 4)
    total = 12 + 8 + len(text) + 8 + len(binary)
    return (b"glTF" + struct.pack("<II", 2, total) + struct.pack("<I", len(text)) + b"JSON"
            + text + struct.pack("<I", len(binary)) + b"BIN\x00" + binary)


def textured_quad(image, texture_info_extra=None, uv_set=0):
    """A quad whose material samples one texture; `image` is the images[0] entry, with
    `bufferView` -1 standing for a view of the checker PNG in the buffer."""
    buffer = Buffer()
    positions = buffer.view(floats(QUAD_POSITIONS), target=34962)
    normals = buffer.view(floats(QUAD_NORMALS), target=34962)
    uvs = buffer.view(floats(QUAD_UVS), target=34962)
    indices = buffer.view(struct.pack("<6H", 0, 1, 2, 0, 2, 3), target=34963)
    image = dict(image)
    if image.get("bufferView") == -1:
        image["bufferView"] = buffer.view(CHECKER)
    texture_info = {"index": 0, "texCoord": uv_set}
    texture_info.update(texture_info_extra or {})
    doc = document(
        buffer,
        accessors=[
            vec3(positions, 4, **QUAD_MIN_MAX),
            vec3(normals, 4),
            {"bufferView": uvs, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": indices, "componentType": 5123, "count": 6, "type": "SCALAR"},
        ],
        images=[image],
        samplers=[{"magFilter": 9728, "minFilter": 9987, "wrapS": 33071, "wrapT": 33648}],
        textures=[{"sampler": 0, "source": 0, "name": "checker"}],
        materials=[{
            "name": "checker",
            "alphaMode": "MASK",
            "alphaCutoff": 0.25,
            "doubleSided": True,
            "pbrMetallicRoughness": {"baseColorTexture": texture_info,
                                     "baseColorFactor": [1, 0.5, 0.5, 1]},
        }],
        meshes=[{"primitives": [{
            "attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_%d" % uv_set: 2},
            "indices": 3,
            "material": 0,
        }]}],
        nodes=[{"mesh": 0, "name": "quad"}],
        scenes=[{"nodes": [0]}],
        scene=0,
    )
    return doc, buffer


def triangle(accessor_changes=None, view_stride=None):
    """One triangle, its POSITION accessor changed by `accessor_changes`."""
    buffer = Buffer()
    view = buffer.view(floats([0, 0, 0, 1, 0, 0, 0, 1, 0]), stride=view_stride)
    accessor = vec3(view, 3, min=[0, 0, 0], max=[1, 1, 0])
    accessor.update(accessor_changes or {})
    accessor = {key: value for key, value in accessor.items() if value is not None}
    return document(
        buffer,
        accessors=[accessor],
        meshes=[{"primitives": [{"attributes": {"POSITION": 0}}]}],
        nodes=[{"mesh": 0}],
        scenes=[{"nodes": [0]}],
    ), buffer


def sparse_morph_skin():
    """A quad with a view-less sparse accessor, morph targets, a skin and an animation."""
    buffer = Buffer()
    positions = buffer.view(floats(QUAD_POSITIONS))
    sparse_indices = buffer.view(struct.pack("<2B", 1, 3) + b"\x00\x00")
    sparse_values = buffer.view(floats([2, 0, 0, 0, 2, 0]))
    joints = buffer.view(struct.pack("<16B", *([0, 1, 0, 0] * 4)))
    weights = buffer.view(floats([0.5, 0.5, 0, 0] * 4))
    inverse_binds = buffer.view(floats([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1] * 2))
    times = buffer.view(floats([0, 1]))
    rotations = buffer.view(floats([0, 0, 0, 1, 0, 0.7071, 0, 0.7071]))
    colors = buffer.view(struct.pack("<16H", *([65535, 0, 32768, 65535] * 4)))
    sparse = {"count": 2, "indices": {"bufferView": sparse_indices, "componentType": 5121},
              "values": {"bufferView": sparse_values}}
    return document(
        buffer,
        accessors=[
            vec3(positions, 4, **QUAD_MIN_MAX),
            # Zeros but for two displaced vertices: no bufferView, only the sparse part.
            {"componentType": 5126, "count": 4, "type": "VEC3", "sparse": sparse,
             "min": [0, 0, 0], "max": [2, 2, 0]},
            {"bufferView": joints, "componentType": 5121, "count": 4, "type": "VEC4"},
            {"bufferView": weights, "componentType": 5126, "count": 4, "type": "VEC4"},
            {"bufferView": inverse_binds, "componentType": 5126, "count": 2, "type": "MAT4"},
            {"bufferView": times, "componentType": 5126, "count": 2, "type": "SCALAR",
             "min": [0], "max": [1]},
            {"bufferView": rotations, "componentType": 5126, "count": 2, "type": "VEC4"},
            {"bufferView": colors, "componentType": 5123, "normalized": True, "count": 4,
             "type": "VEC4"},
            # The base positions again, with a sparse part over them.
            vec3(positions, 4, min=[0, 0, 0], max=[2, 2, 0], sparse=sparse),
        ],
        meshes=[
            {"name": "morphed", "weights": [0.5], "primitives": [{
                "attributes": {"POSITION": 0, "JOINTS_0": 2, "WEIGHTS_0": 3, "COLOR_0": 7},
                "targets": [{"POSITION": 1}],
                "mode": 6,
            }]},
            {"name": "sparse only", "primitives": [{"attributes": {"POSITION": 1}, "mode": 5}]},
            {"name": "sparse over a base", "primitives": [{"attributes": {"POSITION": 8}}]},
        ],
        skins=[{"joints": [1, 2], "inverseBindMatrices": 4, "skeleton": 1}],
        nodes=[
            {"mesh": 0, "skin": 0, "children": [1]},
            {"name": "joint", "children": [2], "rotation": [0, 0, 0, 1]},
            {"name": "tip", "translation": [0, 1, 0]},
            {"mesh": 1, "scale": [1, 1, 1]},
            {"mesh": 2, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 3, 0, 0, 1]},
        ],
        animations=[{
            "samplers": [{"input": 5, "output": 6, "interpolation": "LINEAR"}],
            "channels": [{"sampler": 0, "target": {"node": 1, "path": "rotation"}}],
        }],
        scenes=[{"nodes": [0]}, {"nodes": [3, 4], "name": "second"}],
        scene=1,
    )


def interleaved():
    """Interleaved positions and normals (byteStride 24), 8-bit indices, a strip and a point
    primitive, a camera, several scenes and no default one."""
    buffer = Buffer()
    vertices = []
    for i in range(4):
        vertices += QUAD_POSITIONS[3 * i:3 * i + 3] + QUAD_NORMALS[3 * i:3 * i + 3]
    interleaved_view = buffer.view(floats(vertices), stride=24, target=34962)
    indices = buffer.view(struct.pack("<6B", 0, 1, 2, 0, 2, 3), target=34963)
    uvs = buffer.view(struct.pack("<8H", *[65535 * int(c) for c in QUAD_UVS]))
    doc = document(
        buffer,
        uri=False,
        accessors=[
            vec3(interleaved_view, 4, **QUAD_MIN_MAX),
            vec3(interleaved_view, 4, byteOffset=12),
            {"bufferView": indices, "componentType": 5121, "count": 6, "type": "SCALAR"},
            {"bufferView": uvs, "componentType": 5123, "normalized": True, "count": 4,
             "type": "VEC2"},
        ],
        meshes=[{"primitives": [
            {"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 3}, "indices": 2},
            {"attributes": {"POSITION": 0}, "mode": 5},
            {"attributes": {"POSITION": 0}, "mode": 0},
        ]}],
        cameras=[{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.01}}],
        nodes=[{"mesh": 0}, {"camera": 0, "translation": [0, 0, 5]}, {"mesh": 0, "children": [1]}],
        scenes=[{"nodes": [0]}, {"nodes": [2]}],
    )
    return doc, buffer


def write(path, content):
    path = os.path.join(ROOT, path)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb") as out:
        out.write(content if isinstance(content, bytes) else
                  json.dumps(content, separators=(",", ":")).encode())


def main():
    # Seeds: each reaches a part of the glTF reader the campaigns' queues had not.
    view_doc, view_buffer = textured_quad(
        {"bufferView": -1, "mimeType": "image/png", "name": "checker in a view"},
        {"extensions": {"KHR_texture_transform": {
            "offset": [0.5, 0], "rotation": 0.3, "scale": [2, 2], "texCoord": 1}}},
        uv_set=1)
    view_doc["extensionsUsed"] = ["KHR_texture_transform"]
    uri_doc, _ = textured_quad(
        {"uri": "data:image/png;base64," + base64.b64encode(CHECKER).decode(),
         "mimeType": "image/png"})
    file_doc, _ = textured_quad({"uri": "checker%20missing.png"})
    morph_doc = sparse_morph_skin()
    interleaved_doc, interleaved_buffer = interleaved()
    seeds = {
        "texture-in-view.glb": glb(view_doc, view_buffer),
        "texture-data-uri.gltf": uri_doc,
        "texture-file-uri.gltf": file_doc,
        "sparse-morph-skin-scenes.gltf": morph_doc,
        "interleaved-strip-points.glb": glb(interleaved_doc, interleaved_buffer),
    }
    for target in ("gltf", "scene_load"):
        for name, content in seeds.items():
            write(os.path.join("corpus", target, name), content)

    # Findings: each made cadr panic (or abort) before it was refused.
    no_mime, no_mime_buffer = textured_quad({"bufferView": -1, "mimetype": "image/png"})
    write("findings/gltf/image-buffer-view-without-mime-type.glb", glb(no_mime, no_mime_buffer))
    write("findings/gltf/image-without-uri-or-buffer-view.gltf",
          textured_quad({"name": "nowhere"})[0])
    write("findings/gltf/byte-stride-shorter-than-element.gltf",
          triangle(view_stride=4)[0])
    sparse_stride, _ = triangle({"sparse": {
        "count": 1, "indices": {"bufferView": 1, "componentType": 5121},
        "values": {"bufferView": 2}}})
    sparse_stride["bufferViews"] += [
        {"buffer": 0, "byteOffset": 0, "byteLength": 1},
        {"buffer": 0, "byteOffset": 0, "byteLength": 36, "byteStride": 4},
    ]
    write("findings/gltf/sparse-values-with-byte-stride.gltf", sparse_stride)
    huge_view, huge_buffer = textured_quad({"bufferView": -1, "mimeType": "image/png"})
    huge_view["bufferViews"][-1]["byteOffset"] = 2**64 - 8
    huge_view["bufferViews"][-1]["byteLength"] = 16
    write("findings/gltf/buffer-view-end-past-u64.glb", glb(huge_view, huge_buffer))
    write("findings/gltf/viewless-accessor-of-four-billion-elements.gltf",
          triangle({"bufferView": None, "count": 4_000_000_000, "sparse": {
              "count": 1, "indices": {"bufferView": 0, "componentType": 5121},
              "values": {"bufferView": 0}}})[0])


if __name__ == "__main__":
    main()
