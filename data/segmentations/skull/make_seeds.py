#!/usr/bin/env python3
"""Writes seeds.json, the seeds of the skull CT's labels, from the boxes below.

usage: make_seeds.py CRANIUM.inv3 OUT.json

Not run at set-up: set-up runs `anatomy-tutor segment skull --seeds seeds.json` on the kept file
(scripts/label-scans.sh). This is how that file was made, kept so the seeds can be changed and
remade (about a minute, pure Python). Each structure is a tissue range (HU), a box of voxels
(i, j, k inclusive, found on `anatomy-tutor slice skull` images; docs/skull_landmarks.md) and a
voxel inside it: the voxels of that range connected to the voxel inside the box (or all of them
in the box where no voxel is given; orbits also inside a cone from the apex and behind their opening, OPENING) are
the structure's core (the temporal line's: the outer table along an arch, ARC below). Seeds are runs along i of core voxels on every 3rd row and 2nd slice; the
background gets runs on every 4th row and 2nd slice of the voxels at least 3 voxels in-plane from
every core. `anatomy-tutor segment --method grow` then gives every voxel the label of the seed it
reaches most cheaply (gradient weights), which fills the gaps and sets the boundaries.
"""
import array, json, sys, tarfile
from collections import deque

with tarfile.open(sys.argv[1]) as tar:
    member = next(m for m in tar.getmembers() if m.name.endswith('matrix.dat'))
    a = array.array('h'); a.frombytes(tar.extractfile(member).read())
if sys.byteorder != 'little': a.byteswap()
NI, NJ, NK = 256, 256, 108
assert len(a) == NI * NJ * NK, 'not the 256x256x108 Cranium.inv3'
SP = 0.95703119999999997
def v(i, j, k): return a[(k * NJ + j) * NI + i]
# The loader's LPS millimetres (docs/skull_landmarks.md), rounded to 0.01 mm.
def mm(i, j, k): return (round((i - 127.5) * SP, 2), round(-(j - 127.5) * SP, 2), round((k - 53.5) * 1.5, 2))

AIR = (-1100, -400); AIR_ANY = [-2000, -400]; BONE = (300, 1800); DENSE = (1000, 4000); SOFT = (-150, 100); ANYBONE = (300, 4000); BONE_ANY = [300, 4000]; ENAMEL = (1800, 4000); ARCH = [200, 4000]
# value, id, colour, [(range, box (i0,i1,j0,j1,k0,k1), start voxel or None = all in box)]
S = [
 (1, 'Upper teeth', [0.95,0.93,0.80], [(ENAMEL, (80,179,150,224,0,13), None)]),
 (2, 'Mandible', [0.85,0.70,0.45], [(BONE, (68,95,126,169,0,21), (84,148,8)), (BONE, (158,190,126,169,0,21), (179,150,8))]),
 # The alveolar process and palate; the sinus walls and the orbital floor on each side of the
 # septum (k 20-29); the frontal processes beside the nasal aperture (k 26-38; the growth takes
 # them on up to the nasion), behind the nasal bones at the front of the bridge (j > 212, left
 # unlabelled).
 (3, 'Maxilla', [0.90,0.55,0.35], [(BONE, (90,164,165,221,4,23), (132,192,12)),
                                   (BONE, (80,124,165,221,20,29), None), (BONE, (133,176,165,221,20,29), None),
                                   (BONE, (104,124,188,212,26,38), None), (BONE, (133,153,188,212,26,38), None)]),
 (4, 'Zygomatic arch (right)', [0.75,0.55,0.85], [(ARCH, (58,70,130,172,22,28), (64,155,27))]),
 (5, 'Zygomatic arch (left)', [0.55,0.45,0.90], [(ARCH, (186,202,130,172,22,28), (196,150,28))]),
 # The airway from the palate up, with the narrow cleft beside the septum between the two ethmoid
 # labyrinths in front (i 128-132, j 168-200), which the growth takes on up to the cribriform plate.
 (6, 'Nasal cavity', [0.30,0.75,0.95], [(AIR, (113,139,150,214,8,29), None), (AIR, (128,132,168,200,30,40), None)]),
 (7, 'Maxillary sinus (right)', [0.20,0.85,0.55], [(AIR, (80,112,150,209,0,39), (108,176,21))]),
 (8, 'Maxillary sinus (left)', [0.55,0.90,0.20], [(AIR, (140,174,150,209,0,39), (155,181,23))]),
 (9, 'Frontal sinus', [0.95,0.85,0.25], [(AIR, (105,149,175,214,42,69), (128,199,55))]),
 (10, 'Sphenoid sinus', [0.95,0.45,0.65], [(AIR, (110,149,128,155,20,39), (130,148,31))]),
 # Both labyrinths: in front (j 168-194) the air on each side of that cleft, behind it the wider
 # posterior cells across the midline.
 (11, 'Ethmoid air cells', [0.40,0.55,0.95], [(AIR, (110,127,150,194,30,43), None), (AIR, (133,144,150,194,30,43), None)]),
 (12, 'Orbit (right)', [0.95,0.35,0.30], [(SOFT, (72,112,150,206,26,52), (93,179,39), ((112,158,38),(91,205,40),4,19))]),
 (13, 'Orbit (left)', [0.30,0.35,0.95], [(SOFT, (143,183,150,206,26,52), (163,182,40), ((143,158,38),(164,205,40),4,19))]),
 # The canals from the concha to the isthmus before the eardrum (right i 60-86, left i 170-199), at
 # their own level (k 15-23): the tympanic cavity and attic medial and above them are left out.
 (14, 'External acoustic meatus (right)', [0.95,0.60,0.10], [(AIR, (60,86,106,126,15,23), (75,118,21))]),
 (15, 'External acoustic meatus (left)', [0.10,0.60,0.95], [(AIR, (170,199,106,126,15,23), (182,116,21))]),
 (16, 'Mastoid air cells (right)', [0.85,0.30,0.60], [(AIR, (62,84,85,115,8,33), None)]),
 (17, 'Mastoid air cells (left)', [0.60,0.30,0.85], [(AIR, (155,193,85,115,8,33), None)]),
 # The dense bone around the inner ear, and the pyramid's less dense part running forward and
 # medially from it to the apex beside the clivus (300 HU and up inside a cone from the apex,
 # radius 3 mm, to the dense part, 9 mm; axial slices k 20-32 show its ridge).
 (18, 'Petrous temporal bone (right)', [0.95,0.90,0.55], [(DENSE, (80,117,100,134,14,27), (94,112,23)),
                                                          (ANYBONE, (80,121,98,130,14,32), (94,112,23), ((117,123,28),(88,110,22),3,9))]),
 (19, 'Petrous temporal bone (left)', [0.75,0.90,0.55], [(DENSE, (140,177,100,134,14,27), (167,113,23)),
                                                         (ANYBONE, (138,177,98,130,14,32), (167,113,23), ((142,124,28),(170,110,22),3,9))]),
 (20, 'Atlas (C1)', [0.60,0.80,0.70], [(ANYBONE, (98,116,100,127,0,2), None), (ANYBONE, (140,159,100,127,0,2), None), (ANYBONE, (118,138,123,131,0,7), None)]),
 (21, 'Axis (C2)', [0.70,0.65,0.95], [(ANYBONE, (122,135,108,121,0,6), (129,119,3))]),
 # The bone of each ramus in front of the mandibular notch, from the notch's lowest level (k 17) up
 # to the tip under the zygomatic arch (k 25); listed after the mandible, but its core wins (FIRST).
 (22, 'Coronoid process (right)', [0.95,0.75,0.30], [(BONE, (74,92,152,171,17,27), (82,164,23))]),
 (23, 'Coronoid process (left)', [0.95,0.55,0.20], [(BONE, (172,190,152,171,17,27), (180,165,23))]),
 # A region for Fig. 6 (the temporal line outlined): the outer table of the left side of the vault
 # along the superior temporal line, where the temporalis fascia attaches. The line is not a ridge
 # this 1 mm CT shows, so its course is drawn as anatomy places it: an arch over the temporal fossa
 # from the zygomatic process of the frontal bone (above the lateral orbital rim, k 48) up to its
 # highest point (j 130, k 80, about 8 cm above the zygomatic arch) and down behind the ear to the
 # supramastoid crest (j 92, k 35) — ARC below; a strip about 5 mm wide and 3 voxels deep.
 (24, 'Temporal line (left)', [0.35,0.80,0.95], [('arc',)]),
]
# The temporal line's arch (voxels): its top, the half-widths in j in front of and behind the top,
# the level of its ends (k) and of its front end (the frontal bone above the orbit), the strip's
# half-width as a share of the arch's radius, and the outer table's depth (voxels of bone from the
# skull's outer surface inward along i, the left side), and the least i of that surface: at the
# front of the vault the first bone outward from the middle is the forehead beside the frontal
# sinus, which faces forward; the line runs on the side of the skull.
ARC = dict(jtop=130, ktop=80, aj_front=68, aj_back=38, kend=35, kfront=48, halfwidth=0.045, depth=3, imin=170)
FIRST = ('Coronoid process (right)', 'Coronoid process (left)')

def outer_table_arc(a):
    # The left vault's outer surface per row (k, j): from the middle (i 128) outward, the first bone
    # and the bone after it with gaps of at most 3 voxels (the diploe); what lies beyond a wider gap
    # (the scalp, the head holder behind the occiput) is not the skull.
    out = set()
    for k in range(a['kend'], NK):
        for j in range(NJ):
            front = j >= a['jtop']
            if front and k < a['kfront']: continue
            aj = a['aj_front'] if front else a['aj_back']
            r = (((j - a['jtop']) / aj) ** 2 + ((k - a['kend']) / (a['ktop'] - a['kend'])) ** 2) ** 0.5
            if abs(r - 1) > a['halfwidth']: continue
            last = None
            for i in range(128, NI):
                if BONE_ANY[0] <= v(i, j, k):
                    if last is not None and i - last > 3: break
                    last = i
            if last is None or last < a['imin']: continue
            for i in range(last - a['depth'] + 1, last + 1):
                if BONE_ANY[0] <= v(i, j, k): out.add((i, j, k))
    return out
# Labels that keep only voxels of a tissue range (the seeds file's "grow_range",
# segment/ranged_growth.h): the bones, so a thin ramus or arch is not padded with the muscle and air
# around it, and the ear canals and ethmoid cells, which keep their air and not the skin of their
# walls or the cells' bony septa and lining.
GROW_RANGE = {'Mandible': BONE_ANY, 'Maxilla': BONE_ANY, 'Zygomatic arch (right)': ARCH, 'Zygomatic arch (left)': ARCH,
              'Atlas (C1)': BONE_ANY, 'Axis (C2)': BONE_ANY, 'Coronoid process (right)': BONE_ANY,
              'Coronoid process (left)': BONE_ANY, 'Temporal line (left)': BONE_ANY,
              'Petrous temporal bone (right)': BONE_ANY, 'Petrous temporal bone (left)': BONE_ANY,
              'Ethmoid air cells': AIR_ANY, 'External acoustic meatus (right)': AIR_ANY, 'External acoustic meatus (left)': AIR_ANY}

# The orbital opening: an orbit is the cavity behind the line from its medial rim (the frontal
# process of the maxilla beside the nose) to its lateral rim (the zygomatic bone), in (i, j) on axial
# slices k 32-48 (the rims' foremost bone). The eyelids, the front of the globe and the skin of the
# brow and cheek in front of that line are left out, so from the front the rim frames the orbit.
OPENING = {'Orbit (right)': ((115, 196), (79, 188)), 'Orbit (left)': ((141, 196), (178, 188))}
def behind_opening(medial, lateral):
    (im, jm), (il, jl) = medial, lateral
    return lambda i, j, k: j <= jm + (jl - jm) * (i - im) / (il - im)

def inside(b, i, j, k): return b[0] <= i <= b[1] and b[2] <= j <= b[3] and b[4] <= k <= b[5]
def cone(apex, front, r0, r1):
    A = (apex[0]*0.957, apex[1]*0.957, apex[2]*1.5); F = (front[0]*0.957, front[1]*0.957, front[2]*1.5)
    ax = [F[n]-A[n] for n in range(3)]; L2 = sum(c*c for c in ax)
    def inside(i, j, k):
        p = (i*0.957 - A[0], j*0.957 - A[1], k*1.5 - A[2])
        t = sum(p[n]*ax[n] for n in range(3)) / L2
        if t < 0 or t > 1.05: return False
        d2 = sum((p[n] - t*ax[n])**2 for n in range(3))
        r = r0 + (r1 - r0) * min(t, 1.0)
        return d2 <= r*r
    return inside
def comp(rng, b, start, keep=lambda i, j, k: True):
    ok = lambda i, j, k: rng[0] <= v(i, j, k) <= rng[1] and keep(i, j, k)
    out = set()
    if start is None:
        for k in range(b[4], b[5]+1):
            for j in range(b[2], b[3]+1):
                for i in range(b[0], b[1]+1):
                    if ok(i, j, k): out.add((i, j, k))
        return out
    assert ok(*start), (start, v(*start))
    q = deque([start]); out.add(start)
    while q:
        i, j, k = q.popleft()
        for d in ((1,0,0),(-1,0,0),(0,1,0),(0,-1,0),(0,0,1),(0,0,-1)):
            n = (i+d[0], j+d[1], k+d[2])
            if n not in out and inside(b, *n) and ok(*n): out.add(n); q.append(n)
    return out

owner = {}   # voxel -> label id (first listed wins)
for value, name, colour, parts in sorted(S, key=lambda s: s[1] not in FIRST):
    for part in parts:
        if part[0] == 'arc':
            for p in outer_table_arc(ARC): owner.setdefault(p, name)
            continue
        rng, b, start = part[:3]
        keep = cone(*part[3]) if len(part) > 3 else (lambda i, j, k: True)
        if name in OPENING:
            in_cone, behind = keep, behind_opening(*OPENING[name])
            keep = lambda i, j, k, c=in_cone, b=behind: c(i, j, k) and b(i, j, k)
        for p in comp(rng, b, start, keep): owner.setdefault(p, name)

def near_structure(i, j, k, r=2):
    for dk in range(-1, 2):
        for dj in range(-r, r+1):
            for di in range(-r, r+1):
                if (i+di, j+dj, k+dk) in owner: return True
    return False

strokes = {s[1]: [] for s in S}; strokes['background'] = []
def runs(name, pred, jstep, kstep, joff=0):
    # segments along i of voxels satisfying pred, on every jstep-th row and kstep-th slice
    for k in range(0, NK, kstep):
        for j in range(joff, NJ, jstep):
            i = 0
            while i < NI:
                if pred(i, j, k):
                    i0 = i
                    while i + 1 < NI and pred(i + 1, j, k): i += 1
                    strokes[name].append([mm(i0, j, k), mm(i, j, k)] if i > i0 else [mm(i0, j, k)])
                i += 1
for value, name, colour, parts in S:
    runs(name, lambda i, j, k, n=name: owner.get((i, j, k)) == n, 3, 2)
    for part in parts:
        start = part[2] if part[0] != 'arc' else None
        if start: strokes[name].append([mm(*start)])
boxes = [p[1] for s in S for p in s[3] if p[0] != 'arc']
def nearbox(i, j, k, m):
    return any(b[0]-m <= i <= b[1]+m and b[2]-m <= j <= b[3]+m and b[4]-m//2 <= k <= b[5]+m//2 for b in boxes)
def bg(i, j, k):
    return not near_structure(i, j, k)
runs('background', bg, 4, 2, 1)
value_of = {s[1]: s[0] for s in S}; value_of["background"] = 0
labels = [{"value": 0, "name": "background"}] + [dict({"value": s[0], "name": s[1], "colour": s[2]},
            **({"grow_range": GROW_RANGE[s[1]]} if s[1] in GROW_RANGE else {})) for s in S]
lines = ['{', '  "schema": 1,', '  "space": "LPS",', '  "labels": [']
lines += ['    ' + json.dumps(l) + (',' if n + 1 < len(labels) else '') for n, l in enumerate(labels)]
lines += ['  ],', '  "strokes": [']
out = []
for name, pts in strokes.items():
    for p in pts:
        out.append('    ' + json.dumps({"label": value_of[name], "points": [list(q) for q in p]}, separators=(',', ':')))
# The base these strokes were drawn and reviewed with (the growth's data-derived default differs).
lines += [',\n'.join(out), '  ],', '  "grow": {"base": 0.05}', '}']
open(sys.argv[2], 'w').write('\n'.join(lines) + '\n')
print('seeds: ' + ', '.join('%s %d' % (k, len(p)) for k, p in strokes.items()), file=sys.stderr)
