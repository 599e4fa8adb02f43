#!/usr/bin/env python3
"""Checks binary glTF 2.0 files (.glb) against the layout rules of the glTF 2.0 specification
(section 4.4, GLB file format, and the accessor rules of 3.6): the 12-byte header (magic
'glTF', version 2, total length), a JSON chunk then at most one BIN chunk, 4-byte aligned;
asset.version 2.0; every bufferView inside its buffer, every accessor inside its bufferView,
POSITION accessors with min and max that hold their values, indices below their vertex count,
triangle lists a multiple of 3 long. Exit status 0 when every file passes.

  glb.py FILE.glb...
"""
import json
import struct
import sys

COMPONENT = {5120: ('b', 1), 5121: ('B', 1), 5122: ('h', 2), 5123: ('H', 2), 5125: ('I', 4), 5126: ('f', 4)}
TYPE = {'SCALAR': 1, 'VEC2': 2, 'VEC3': 3, 'VEC4': 4, 'MAT4': 16}


def check(path):
    data = open(path, 'rb').read()
    problems = []
    magic, version, length = struct.unpack_from('<III', data, 0)
    if magic != 0x46546C67 or version != 2 or length != len(data):
        return ['header: magic %x version %d length %d (file %d bytes)' % (magic, version, length, len(data))]
    offset, chunks = 12, []
    while offset < len(data):
        size, kind = struct.unpack_from('<II', data, offset)
        if size % 4:
            problems.append('chunk at %d: length %d is not 4-byte aligned' % (offset, size))
        chunks.append((kind, data[offset + 8:offset + 8 + size]))
        offset += 8 + size
    if not chunks or chunks[0][0] != 0x4E4F534A:
        return problems + ['the first chunk is not JSON']
    if len(chunks) > 2 or (len(chunks) == 2 and chunks[1][0] != 0x004E4942):
        problems.append('more than one BIN chunk, or a second chunk that is not BIN')
    gltf = json.loads(chunks[0][1].decode('utf-8'))
    if gltf.get('asset', {}).get('version') != '2.0':
        problems.append('asset.version is not 2.0')
    binary = chunks[1][1] if len(chunks) == 2 else b''
    buffers = gltf.get('buffers', [])
    for i, b in enumerate(buffers):
        if i == 0 and 'uri' not in b and b['byteLength'] > len(binary):
            problems.append('buffer 0: %d bytes, the BIN chunk %d' % (b['byteLength'], len(binary)))
    views = gltf.get('bufferViews', [])
    for i, v in enumerate(views):
        if v.get('byteOffset', 0) + v['byteLength'] > buffers[v['buffer']]['byteLength']:
            problems.append('bufferView %d runs past its buffer' % i)
    accessors = gltf.get('accessors', [])
    values = []
    for i, a in enumerate(accessors):
        view = views[a['bufferView']]
        fmt, size = COMPONENT[a['componentType']]
        n = TYPE[a['type']]
        stride = view.get('byteStride', size * n)
        start = view.get('byteOffset', 0) + a.get('byteOffset', 0)
        end = start + stride * (a['count'] - 1) + size * n
        if end > view.get('byteOffset', 0) + view['byteLength']:
            problems.append('accessor %d runs past its bufferView' % i)
            values.append([])
            continue
        values.append([struct.unpack_from('<' + fmt * n, binary, start + stride * k) for k in range(a['count'])])
    for m, mesh in enumerate(gltf.get('meshes', [])):
        for p in mesh['primitives']:
            position = p['attributes']['POSITION']
            a = accessors[position]
            if 'min' not in a or 'max' not in a:
                problems.append('mesh %d: POSITION without min/max' % m)
            else:
                for v in values[position]:
                    if any(v[k] < a['min'][k] - 1e-6 or v[k] > a['max'][k] + 1e-6 for k in range(3)):
                        problems.append('mesh %d: a position outside its min/max' % m)
                        break
            if 'indices' in p:
                idx = [v[0] for v in values[p['indices']]]
                if any(i >= a['count'] for i in idx):
                    problems.append('mesh %d: an index past the vertex count' % m)
                if p.get('mode', 4) == 4 and len(idx) % 3:
                    problems.append('mesh %d: a triangle list of %d indices' % (m, len(idx)))
    for n, node in enumerate(gltf.get('nodes', [])):
        if 'mesh' in node and not 0 <= node['mesh'] < len(gltf.get('meshes', [])):
            problems.append('node %d: no mesh %d' % (n, node['mesh']))
        for c in node.get('children', []):
            if not 0 <= c < len(gltf['nodes']):
                problems.append('node %d: no child %d' % (n, c))
    return problems


def main():
    failed = 0
    for path in sys.argv[1:]:
        problems = check(path)
        for p in problems:
            print('%s: %s' % (path, p))
        if problems:
            failed += 1
        else:
            print('%s validates' % path)
    sys.exit(1 if failed else 0)


if __name__ == '__main__':
    main()
