#!/usr/bin/env python3
"""Estimate the bytes a 3d-tiles-renderer page loads for its first (framed) view:
REPLACE refinement where screen-space error > errorTarget (16 px, the renderer's
default), the camera framed as delivery/web/viewer.js frames it. Not a browser
measurement: frustum culling is ignored (the framed view sees the whole model)."""
import json, math, os, sys
folder, width, height = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
model_bytes = os.path.getsize(sys.argv[4]) if len(sys.argv) > 4 else 0
ts = json.load(open(os.path.join(folder, 'tileset.json')))
root = ts['root']
def box(t):
    b = t['boundingVolume']['box']; c = b[0:3]; h = [b[3], b[7], b[11]]
    return c, h
c, h = box(root)
radius = math.sqrt(sum(x * x for x in h))
fov = math.radians(30)
aspect = width / height
distance = radius / math.sin(fov / 2) / min(1, aspect)
eye = [c[0], c[1], c[2] + distance]  # z-up tileset, viewer looks down -z in glTF's y-up: both frames' +z here is approximate
def dist(t):
    cc, hh = box(t)
    d2 = 0
    for k in range(3):
        e = max(abs(eye[k] - cc[k]) - abs(hh[k]), 0)
        d2 += e * e
    return max(math.sqrt(d2), 1e-9)
def size(t):
    u = t.get('content', {}).get('uri')
    return os.path.getsize(os.path.join(folder, u)) if u else 0
drawn = ancestors = 0
tiles = 0
def visit(t, depth):
    global drawn, ancestors, tiles
    sse = t['geometricError'] * height / (2 * dist(t) * math.tan(fov / 2))
    kids = t.get('children', [])
    if sse > 16 and kids:
        ancestors += size(t)
        for k in kids: visit(k, depth + 1)
    else:
        drawn += size(t); tiles += 1
visit(root, 0)
total = sum(os.path.getsize(os.path.join(dp, f)) for dp, _, fs in os.walk(folder) for f in fs if f.endswith('.glb'))
print(f'{width}x{height}: {tiles} tiles drawn, {drawn/1e6:.2f} MB drawn, {(drawn+ancestors)/1e6:.2f} MB with their ancestors; '
      f'tileset {total/1e6:.1f} MB (1/{total/(drawn+ancestors):.0f})' + (f', model {model_bytes/1e6:.0f} MB (1/{model_bytes/(drawn+ancestors):.0f})' if model_bytes else ''))
