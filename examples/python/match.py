#!/usr/bin/env python3
"""The Python version of affine_orb_match: Affine-ORB features of two images, Hamming matches,
homography or fundamental matrix, correct matches against a ground-truth homography.

    PYTHONPATH=<build>/python /usr/bin/python3 examples/python/match.py [IMG1 IMG2 [H1TO2]]
        [--features N] [--max-tilt T] [--threads K] [--out matches.png] [--rectified rectified.png]

Without images it uses Debian opencv-doc's graf1.png, graf3.png and H1to3p.xml. Matching uses
the strongest corners (spreading="strongest"), ratio 0.8, as the C++ example does."""
import argparse
import os
import sys
import time

import cv2
import numpy as np

import affine_orb

SAMPLES = "/usr/share/doc/opencv-doc/examples/data"


def read_homography(path):
    if path.endswith((".xml", ".yml", ".yaml")):
        storage = cv2.FileStorage(path, cv2.FILE_STORAGE_READ)
        matrix = storage.getFirstTopLevelNode().mat()
    else:
        matrix = np.loadtxt(path)
    if matrix is None or matrix.shape != (3, 3):
        raise SystemExit("match.py: %s does not hold a 3 x 3 homography" % path)
    return matrix


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("images", nargs="*", help="IMG1 IMG2 [H1TO2]")
    parser.add_argument("--features", type=int, default=1000, help="keypoints from each image (the views add as many)")
    parser.add_argument("--max-tilt", type=float, default=2.0 * 2 ** 0.5, help="largest simulated tilt, 1 = plain")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--out", default="matches.png")
    parser.add_argument("--rectified", default="rectified.png")
    args = parser.parse_args()
    if len(args.images) not in (0, 2, 3):
        parser.error("give two images and optionally a homography, or nothing for the graf pair")
    paths = args.images or [os.path.join(SAMPLES, "graf1.png"), os.path.join(SAMPLES, "graf3.png"),
                            os.path.join(SAMPLES, "H1to3p.xml")]
    images = [cv2.imread(p, cv2.IMREAD_GRAYSCALE) for p in paths[:2]]
    for path, image in zip(paths, images):
        if image is None:
            raise SystemExit("match.py: cannot read %s" % path)

    extractor = affine_orb.Extractor(features=args.features, max_tilt=args.max_tilt, threads=args.threads,
                                     spreading="strongest")
    start = time.perf_counter()
    (k1, d1), (k2, d2) = (extractor.detect_and_compute(image) for image in images)
    ms = (time.perf_counter() - start) * 500.0
    matches = affine_orb.match(d1, d2, ratio=0.8)
    print("keypoints %d / %d, %.1f ms per image, %d matches" % (len(k1), len(k2), ms, len(matches)))
    if len(paths) == 3:
        h = read_homography(paths[2])
        p1 = np.array([k1[m.queryIdx].pt for m in matches], dtype=np.float64).reshape(-1, 1, 2)
        p2 = np.array([k2[m.trainIdx].pt for m in matches])
        mapped = cv2.perspectiveTransform(p1, h).reshape(-1, 2)
        correct = int(np.count_nonzero(np.linalg.norm(mapped - p2, axis=1) < 3.0))
        print("correct (< 3 px from the ground truth): %d of %d" % (correct, len(matches)))
    if len(matches) >= 8:
        result = affine_orb.select_model(np.array([k1[m.queryIdx].pt for m in matches]),
                                         np.array([k2[m.trainIdx].pt for m in matches]))
        print("model %s (R_H = %.2f)" % (result["model"], result["homography_ratio"]))
        if result["homography"] is not None:
            # The second image brought into the first one's frame: x1 ~ H^-1 x2.
            rectified = cv2.warpPerspective(images[1], np.linalg.inv(result["homography"]),
                                            (images[0].shape[1], images[0].shape[0]))
            cv2.imwrite(args.rectified, rectified)
            print("rectified: %s (from the estimated homography%s)" %
                  (args.rectified, "" if result["model"] == "homography" else ", although F was chosen"))
    drawn = cv2.drawMatches(images[0], k1, images[1], k2, matches, None,
                            flags=cv2.DrawMatchesFlags_NOT_DRAW_SINGLE_POINTS)
    cv2.imwrite(args.out, drawn)
    print("matches: %s" % args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
