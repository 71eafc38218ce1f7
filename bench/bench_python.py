#!/usr/bin/env python3
"""Cost of the Python module over the C++ extractor on 640x480 images, in one run.

    PYTHONPATH=<build>/python /usr/bin/python3 bench/bench_python.py <build> [--rounds N]

For graf1 and KITTI 06 frame 10 cut to 640x480 (as bench_affine_speed does), with the default
options (18 views) and plain (max_tilt 1): the median time of Extractor.detect_and_compute() in
Python (keypoints converted to cv2.KeyPoint, descriptors to a numpy array) against the median
time of Extractor::extract() in C++ (the probe program affine_orb_python_probe, same options,
same image file), interleaved round by round.

Then, for the two-view matcher with its defaults on graf 1->3 (verified at stage 0) and EVD girl
(every stage runs): the median time of match_images(), which builds a matcher per call, against
TwoViewMatcher.match() on one matcher built before, interleaved call by call."""
import argparse
import os
import statistics
import subprocess
import tempfile
import time

import cv2

import affine_orb

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared", "data")


def crop_640x480(image):
    scale = max(640 / image.shape[1], 480 / image.shape[0])
    size = (max(640, round(image.shape[1] * scale)), max(480, round(image.shape[0] * scale)))
    scaled = cv2.resize(image, size, interpolation=cv2.INTER_AREA if scale < 1 else cv2.INTER_LINEAR)
    y, x = (scaled.shape[0] - 480) // 2, (scaled.shape[1] - 640) // 2
    return scaled[y:y + 480, x:x + 640].copy()


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("build")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--repeat", type=int, default=9)
    args = parser.parse_args()
    probe = os.path.join(args.build, "adapters", "python", "affine_orb_python_probe")
    images = {
        "graf1": cv2.imread(os.path.join(DATA, "oxford", "graf", "img1.png"), cv2.IMREAD_GRAYSCALE),
        "KITTI 06 frame 10": cv2.imread(os.path.join(DATA, "kitti06", "image_0", "000010.png"), cv2.IMREAD_GRAYSCALE),
    }
    print("| 640x480 image | options | C++ ms | Python ms | ratio |\n|---|---|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as scratch:
        for name, image in images.items():
            if image is None:
                raise SystemExit("cannot read the %s image under %s" % (name, DATA))
            image = crop_640x480(image)
            path = os.path.join(scratch, "image.png")
            cv2.imwrite(path, image)
            for label, tilt in (("18 views, 1000 + 1000", 2.0 * 2 ** 0.5), ("plain, 1000", 1.0)):
                extractor = affine_orb.Extractor(features=1000, max_tilt=tilt)
                extractor.detect_and_compute(image)
                cpp, py = [], []
                for _ in range(args.rounds):
                    out = subprocess.run([probe, path, "1000", repr(tilt), "rbrief", "1", "--time", str(args.repeat)],
                                         check=True, capture_output=True, text=True).stdout
                    cpp.append(float(out))
                    times = []
                    for _ in range(args.repeat):
                        start = time.perf_counter()
                        extractor.detect_and_compute(image)
                        times.append((time.perf_counter() - start) * 1000.0)
                    py.append(statistics.median(times))
                c, p = statistics.median(cpp), statistics.median(py)
                print("| %s | %s | %.2f | %.2f | %.3f |" % (name, label, c, p, p / c))
    two_view_table(args.rounds * args.repeat)


def two_view_table(calls):
    """match_images() against a reused TwoViewMatcher.match(), `calls` interleaved calls each."""
    pairs = {"graf 1->3": ("oxford/graf/img1.png", "oxford/graf/img3.png"),
             "EVD girl": ("pairs/evd/girl/1.png", "pairs/evd/girl/2.png")}
    print("\n| pair | match_images() ms | TwoViewMatcher.match() ms | ratio |\n|---|---:|---:|---:|")
    for name, (path1, path2) in pairs.items():
        image1, image2 = (cv2.imread(os.path.join(DATA, p), cv2.IMREAD_GRAYSCALE) for p in (path1, path2))
        if image1 is None or image2 is None:
            raise SystemExit("cannot read the %s pair under %s" % (name, DATA))
        matcher = affine_orb.TwoViewMatcher()
        matcher.match(image1, image2)
        once, reused = [], []
        for _ in range(calls):
            start = time.perf_counter()
            affine_orb.match_images(image1, image2)
            once.append((time.perf_counter() - start) * 1000.0)
            start = time.perf_counter()
            matcher.match(image1, image2)
            reused.append((time.perf_counter() - start) * 1000.0)
        a, b = statistics.median(once), statistics.median(reused)
        print("| %s | %.1f | %.1f | %.3f |" % (name, a, b, b / a))


if __name__ == "__main__":
    main()
