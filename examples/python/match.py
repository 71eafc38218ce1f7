#!/usr/bin/env python3
"""The Python version of affine_orb_match: two images matched with views on demand
(affine_orb.match_images: plain keypoints first, affine views only while the pair is not verified),
homography or fundamental matrix, correct matches against a ground-truth homography.

    PYTHONPATH=<build>/python /usr/bin/python3 examples/python/match.py [IMG1 IMG2 [H1TO2]]
        [--features N] [--max-tilt T] [--threads K] [--all-stages] [--out matches.png]
        [--rectified rectified.png]

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
    parser.add_argument("--features", type=int, default=2000,
                        help="keypoints from each image itself; the stages of views add 0.25 and 0.5 x as many")
    parser.add_argument("--max-tilt", type=float, default=2.0 * 2 ** 0.5,
                        help="largest simulated tilt, 1 = plain; the stages stop there")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--all-stages", action="store_true", help="run every stage instead of stopping when verified")
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

    stages = [(tilt, share) for tilt, share in ((2.0, 0.25), (2.0 * 2 ** 0.5, 0.5)) if tilt <= args.max_tilt * 1.001]
    start = time.perf_counter()
    r = affine_orb.match_images(images[0], images[1], features=args.features, max_tilt=max(args.max_tilt, 1.0),
                                stages=stages, all_stages=args.all_stages, threads=args.threads)
    ms = (time.perf_counter() - start) * 1000.0
    k1, k2, matches = r["keypoints1"], r["keypoints2"], r["matches"]
    print("%s at stage %d of %d, keypoints %d / %d, %d matches, %.1f ms in all" %
          ("verified" if r["verified"] else "not verified", r["stage"], len(stages), len(k1), len(k2), len(matches), ms))
    if len(paths) == 3:
        h = read_homography(paths[2])
        p1 = np.array([k1[m.queryIdx].pt for m in matches], dtype=np.float64).reshape(-1, 1, 2)
        p2 = np.array([k2[m.trainIdx].pt for m in matches])
        mapped = cv2.perspectiveTransform(p1, h).reshape(-1, 2)
        correct = int(np.count_nonzero(np.linalg.norm(mapped - p2, axis=1) < 3.0))
        print("correct (< 3 px from the ground truth): %d of %d" % (correct, len(matches)))
    print("model %s, %d inliers" % (r["model"], int(np.count_nonzero(r["inliers"]))))
    if r["homography"] is not None:
        # The second image brought into the first one's frame: x1 ~ H^-1 x2.
        rectified = cv2.warpPerspective(images[1], np.linalg.inv(r["homography"]),
                                        (images[0].shape[1], images[0].shape[0]))
        cv2.imwrite(args.rectified, rectified)
        print("rectified: %s (from the estimated homography%s)" %
              (args.rectified, "" if r["model"] == "homography" else ", although F was chosen"))
    drawn = cv2.drawMatches(images[0], k1, images[1], k2, matches, None,
                            flags=cv2.DrawMatchesFlags_NOT_DRAW_SINGLE_POINTS)
    cv2.imwrite(args.out, drawn)
    print("matches: %s" % args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
