#!/usr/bin/env python3
"""Where an exact cut's tips are, through tachi-sim (usage: measure_cut_tips.py TACHI_SIM [STROKES [BLADE]]).

docs/cutting.md, section 8, "Tips". Random slits on a 64 x 64 top-pinned cloth (seeds 1..STROKES, default 100;
BLADE default scalpel): a quadratic path between two points 3 cells or more inside the cloth and 8 or more apart,
bowed by up to a quarter of its length, 1-2 cm in front, 0.2-2 m/s at 60 Hz from t = 0, drawn over the flat rest
grid. Each is run through `tachi-sim --offline --stroke ... --export`; the tips are read from cloth.obj (the
particles on the cut's lips, edges of one face not both on the rim, with no copy at their rest coordinate `vt`)
and compared with the stroke's first and last points' (u, v) on the rest grid, and the exit tip with the cut
path's last point in pattern.svg (the last sample as the cutter located it on the cloth, which moves under
the hand). Prints the distributions in cells, and the strokes beyond 0.1 cell.
"""
import math
import os
import random
import re
import statistics
import subprocess
import sys
import tempfile

N = 64  # particles a side; the cloth is 1 m


def stroke(seed):
    """The stroke of `seed`: its end points in cells, and its samples (t, x, y, z) in seconds and metres."""
    r = random.Random(seed)
    inside = lambda: 3.0 + (N - 7.0) * r.random()
    a = (inside(), inside())
    b = (inside(), inside())
    d = math.dist(a, b)
    if d < 8.0:
        b = (a[0] + 8.0 * (b[0] - a[0]) / d, a[1] + 8.0 * (b[1] - a[1]) / d)
    b = (min(max(b[0], 3.0), N - 4.0), min(max(b[1], 3.0), N - 4.0))
    bow = (r.random() - 0.5) * 0.5
    mid = (0.5 * (a[0] + b[0]) - bow * (b[1] - a[1]), 0.5 * (a[1] + b[1]) + bow * (b[0] - a[0]))
    z = 0.01 + 0.01 * r.random()
    cells_per_sample = (0.2 + 1.8 * r.random()) * (N - 1) / 60.0
    m = max(2, math.ceil(math.dist(a, b) * 1.1 / cells_per_sample))
    spacing = 1.0 / (N - 1)
    samples = []
    for i in range(m + 1):
        s = i / m
        u = (1 - s) ** 2 * a[0] + 2 * (1 - s) * s * mid[0] + s * s * b[0]
        v = (1 - s) ** 2 * a[1] + 2 * (1 - s) * s * mid[1] + s * s * b[1]
        samples.append((i / 60.0, u * spacing - 0.5, 0.5 - v * spacing, z))
    return a, b, samples


def tips(obj):
    """Rest coordinates (cells) of the particles where a cut's two lips meet."""
    uv, faces = [], []
    for line in open(obj):
        if line.startswith('vt '):
            _, x, y = line.split()
            uv.append((float(x) * (N - 1), (1.0 - float(y)) * (N - 1)))
        elif line.startswith('f '):
            faces.append([int(p.split('/')[0]) - 1 for p in line.split()[1:]])
    edges = {}
    for f in faces:
        for k in range(3):
            e = tuple(sorted((f[k], f[(k + 1) % 3])))
            edges[e] = edges.get(e, 0) + 1
    rim = lambda i: min(uv[i]) < 1e-3 or max(uv[i]) > N - 1 - 1e-3
    lips = set()
    for e, count in edges.items():
        if count == 1 and not (rim(e[0]) and rim(e[1])):
            lips.update(e)
    return [uv[i] for i in lips if not any(j != i and math.dist(uv[i], uv[j]) < 1e-3 for j in lips)]


def main():
    exe = sys.argv[1]
    strokes = int(sys.argv[2]) if len(sys.argv) > 2 else 100
    blade = sys.argv[3] if len(sys.argv) > 3 else 'scalpel'
    entry, exit_, exit_path, other = [], [], [], 0
    with tempfile.TemporaryDirectory() as work:
        for seed in range(1, strokes + 1):
            a, b, samples = stroke(seed)
            csv = os.path.join(work, 'stroke.csv')
            with open(csv, 'w') as f:
                f.write('t,x,y,z\n')
                f.writelines('%.6f,%.9f,%.9f,%.9f\n' % s for s in samples)
            out = os.path.join(work, 'out')
            subprocess.run([exe, '--offline', '--grid', str(N), '--pin', 'top-edge', '--blade', blade, '--stroke', csv,
                            '--steps', str(len(samples) + 30), '--export', out], check=True, capture_output=True)
            found = tips(os.path.join(out, 'cloth.obj'))
            if len(found) != 2:  # not one slit (nothing cut, or the blade left the cloth and met it again)
                other += 1
                continue
            entry.append(min(math.dist(t, a) for t in found))
            exit_.append(min(math.dist(t, b) for t in found))
            paths = re.findall(r'class="cut"[^>]*points="([^"]*)"', open(os.path.join(out, 'pattern.svg')).read())
            points = [float(x) for x in paths[-1].split()]
            end = (points[-2] / 1000.0 * (N - 1), points[-1] / 1000.0 * (N - 1))  # mm on the 1 m cloth
            exit_path.append(min(math.dist(t, end) for t in found))
            if max(entry[-1], exit_[-1], exit_path[-1]) > 0.1:
                print('seed %d: entry %.3f exit %.3f (to the path\'s end %.3f) cells' % (seed, entry[-1], exit_[-1],
                                                                                         exit_path[-1]))
    print('%s, %d slits (%d strokes not one slit): entry median %.3f max %.3f, exit median %.3f max %.3f cells; '
          'exit to the cut path\'s end median %.3f max %.3f' % (blade, len(entry), other, statistics.median(entry),
                                                                max(entry), statistics.median(exit_), max(exit_),
                                                                statistics.median(exit_path), max(exit_path)))


if __name__ == '__main__':
    main()
