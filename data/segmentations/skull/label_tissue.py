#!/usr/bin/env python3
"""Prints, for each label of the skull's label map, its voxels and the share of them at or above a
HU threshold (300: bone; -400: not air) -- the numbers the review states quote.

usage: label_tissue.py CRANIUM.inv3 LABELS.nii.gz NAMES.json [HU]   (default 300)

The label map is the one scripts/label-scans.sh writes beside the scan (skull.labels.nii.gz and
.names.json); its voxels are in matrix.dat's order (i fastest, then j, then k). Pure Python.
"""
import array, gzip, json, struct, sys, tarfile

with tarfile.open(sys.argv[1]) as tar:
    member = next(m for m in tar.getmembers() if m.name.endswith('matrix.dat'))
    hu = array.array('h'); hu.frombytes(tar.extractfile(member).read())
raw = gzip.open(sys.argv[2]).read()
offset = int(struct.unpack('<f', raw[108:112])[0])
labels = array.array('H'); labels.frombytes(raw[offset:offset + 2 * len(hu)])
if sys.byteorder != 'little': hu.byteswap(); labels.byteswap()
assert len(labels) == len(hu), 'the label map is not on the scan grid'
names = json.load(open(sys.argv[3]))
threshold = int(sys.argv[4]) if len(sys.argv) > 4 else 300
total, above = {}, {}
for label, value in zip(labels, hu):
    if label:
        total[label] = total.get(label, 0) + 1
        if value >= threshold: above[label] = above.get(label, 0) + 1
for label in sorted(total):
    print('%3d %-34s %8d voxels %6.1f %% >= %d HU' % (label, names.get(str(label), '?'), total[label],
                                                     100.0 * above.get(label, 0) / total[label], threshold))
