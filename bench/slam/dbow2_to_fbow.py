#!/usr/bin/env python3
"""dbow2_to_fbow.py IN OUT -- converts a DBoW2 ORB vocabulary in ORB-SLAM2's text format (ORBvoc.txt
layout, plain or .gz) into FBoW's binary format (.fbow), which stella_vslam loads.

The tree is kept as it is: same nodes, same cluster centres (the 32-byte rBRIEF descriptors), same
leaf weights (idf, stored as float), word ids in DBoW2's order (the order of the leaves in the file),
so a descriptor falls in the same word as with DBoW2 (FBoW descends by Hamming distance, first
minimum, as DBoW2 does). Only the scoring differs: stella scores FBoW vectors its own way.

Input, ORB-SLAM2's TemplatedVocabulary::saveToTextFile: a first line "k L scoring weighting", then
one line per node after the root, in node-id order (ids 1, 2, ...): "parent is_leaf d0 .. d31 weight".

Output, FBoW's Vocabulary::toStream (stella-cv/FBoW c6e3c29, x86-64): uint64 55824124, the `params`
struct (120 bytes, native layout below), then `nblocks` blocks of `block_size` bytes. One block per
non-leaf node, in node-id order (the root is block 0): uint16 child count, uint16 1 if every child is
a leaf, uint32 the node's id, the children's descriptors (32 bytes each, k slots from byte 8), then
k 8-byte entries from byte 8 + 32k: uint32 (leaf: 0x80000000 | word id; else the child's block) and
float32 weight (0 for non-leaves).

Checked against FBoW itself: Vocabulary::readFromFile of the converted ../shared/data vocabulary and
transform() of OpenCV ORB descriptors of a KITTI 00 frame give the words of a DBoW2 descent of the text
file (word_dbow2 below) and their idf weights, L2-normalised as FBoW does.

--check N: afterwards, descend N descriptors (the centres of random leaves, each with a few bits
flipped) in both the DBoW2 tree and the written file and require the same word for each.
"""
import argparse
import gzip
import random
import struct
import sys

SIGNATURE = 55824124
DESC_BYTES = 32
ALIGN = 8  # FBoW's alignment for CV_8U descriptors
CV_8UC1 = 0
# char[50] name, (pad 2), u32 alignment, u32 nblocks, (pad 4), u64 desc_size_bytes_wp,
# u64 block_size_bytes_wp, u64 feature_off_start, u64 child_off_start, u64 total_size,
# i32 desc_type, i32 desc_size, u32 k, (pad 4)
PARAMS = struct.Struct("<50s2xII4xQQQQQiiI4x")
assert PARAMS.size == 120


def read_dbow2(path):
    opener = gzip.open if path.endswith(".gz") else open
    with opener(path, "rt") as f:
        head = f.readline().split()
        k, levels = int(head[0]), int(head[1])
        parent, leaf, desc, weight = [-1], [False], [bytes(DESC_BYTES)], [0.0]
        for line in f:
            fields = line.split()
            if not fields:
                continue
            if len(fields) != 3 + DESC_BYTES:
                raise ValueError("node %d: %d fields, expected %d" % (len(parent), len(fields), 3 + DESC_BYTES))
            parent.append(int(fields[0]))
            leaf.append(fields[1] != "0")
            desc.append(bytes(int(v) for v in fields[2:2 + DESC_BYTES]))
            weight.append(float(fields[-1]))
    children = [[] for _ in parent]
    for nid in range(1, len(parent)):
        if not 0 <= parent[nid] < nid:
            raise ValueError("node %d: parent %d is not an earlier node" % (nid, parent[nid]))
        if leaf[parent[nid]]:
            raise ValueError("node %d: its parent %d is a leaf" % (nid, parent[nid]))
        children[parent[nid]].append(nid)
    return k, levels, parent, leaf, desc, weight, children


def convert(k, leaf, desc, weight, children):
    word = {}
    for nid in range(1, len(leaf)):
        if leaf[nid]:
            word[nid] = len(word)
    block_of = {}
    for nid in range(len(leaf)):
        if not leaf[nid]:
            if not children[nid]:
                raise ValueError("node %d is neither a leaf nor has children" % nid)
            if len(children[nid]) > k:
                raise ValueError("node %d has %d children, k = %d" % (nid, len(children[nid]), k))
            block_of[nid] = len(block_of)
    feature_off = ALIGN
    child_off = feature_off + k * DESC_BYTES
    block_size = -(-(feature_off + k * (DESC_BYTES + 8)) // ALIGN) * ALIGN
    data = bytearray(block_size * len(block_of))
    for nid, b in block_of.items():
        start = b * block_size
        kids = children[nid]
        struct.pack_into("<HHI", data, start, len(kids), int(all(leaf[c] for c in kids)), nid)
        for i, c in enumerate(kids):
            data[start + feature_off + i * DESC_BYTES:start + feature_off + (i + 1) * DESC_BYTES] = desc[c]
            if leaf[c]:
                struct.pack_into("<If", data, start + child_off + 8 * i, 0x80000000 | word[c], weight[c])
            else:
                struct.pack_into("<If", data, start + child_off + 8 * i, block_of[c], 0.0)
    params = PARAMS.pack(b"orb", ALIGN, len(block_of), DESC_BYTES, block_size, feature_off, child_off,
                         len(data), CV_8UC1, DESC_BYTES, k)
    return struct.pack("<Q", SIGNATURE) + params + bytes(data), len(word), len(block_of)


def hamming(a, b):
    return bin(int.from_bytes(a, "little") ^ int.from_bytes(b, "little")).count("1")


def word_dbow2(d, leaf, desc, children, words):
    nid = 0
    while not leaf[nid]:
        nid = min(children[nid], key=lambda c: hamming(d, desc[c]))  # first minimum, as DBoW2
    return words[nid]


def word_fbow(d, blob):
    (name, align, nblocks, dsize_wp, block_size, feature_off, child_off, total, dtype, dsize, k
     ) = PARAMS.unpack_from(blob, 8)
    base = 8 + PARAMS.size
    if len(blob) != base + total or total != nblocks * block_size:
        raise ValueError("size mismatch in the written file")
    b = 0
    while True:
        start = base + b * block_size
        n = struct.unpack_from("<H", blob, start)[0]
        best = min(range(n), key=lambda i: hamming(
            d, blob[start + feature_off + i * dsize_wp:start + feature_off + i * dsize_wp + dsize]))
        ident, _ = struct.unpack_from("<If", blob, start + child_off + 8 * best)
        if ident & 0x80000000:
            return ident & 0x7FFFFFFF
        b = ident


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("input", help="DBoW2 text vocabulary (ORB-SLAM2 layout), .txt or .txt.gz")
    parser.add_argument("output", help="FBoW vocabulary to write (.fbow)")
    parser.add_argument("--check", type=int, default=200, metavar="N",
                        help="descriptors to look up in both trees afterwards (default 200, 0: none)")
    args = parser.parse_args()
    k, levels, parent, leaf, desc, weight, children = read_dbow2(args.input)
    blob, nwords, nblocks = convert(k, leaf, desc, weight, children)
    with open(args.output, "wb") as f:
        f.write(blob)
    print("%s: k=%d L=%d, %d nodes, %d words, %d blocks, %d bytes"
          % (args.output, k, levels, len(parent), nwords, nblocks, len(blob)))
    if args.check:
        words = {}
        for nid in range(1, len(leaf)):
            if leaf[nid]:
                words[nid] = len(words)
        rng = random.Random(1)
        leaves = list(words)
        for _ in range(args.check):
            d = bytearray(desc[rng.choice(leaves)])
            for _ in range(rng.randrange(0, 24)):
                d[rng.randrange(DESC_BYTES)] ^= 1 << rng.randrange(8)
            d = bytes(d)
            if word_dbow2(d, leaf, desc, children, words) != word_fbow(d, blob):
                sys.exit("check failed: a descriptor falls in different words")
        print("check: %d descriptors, the same word in both" % args.check)


if __name__ == "__main__":
    main()
