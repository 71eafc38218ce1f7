"""Tests of the Python module affine_orb (adapters/python): the same output as the C++ extractor,
cv2 interplay, bad input, thread counts. Run by ctest (test_python) with PYTHONPATH set to the
build's python directory and AFFINE_ORB_TEST_PROBE naming the C++ probe program."""
import os
import re
import subprocess
import threading

import cv2
import numpy as np
import pytest

import affine_orb

from conftest import DATA

SAMPLES = os.environ.get("AFFINE_ORB_OPENCV_SAMPLES_DIR", "/usr/share/doc/opencv-doc/examples/data")
PROBE = os.environ.get("AFFINE_ORB_TEST_PROBE")
# opencv-doc's graf1.png and graf3.png are Oxford's graf img1 and img3; aloeL.jpg (Middlebury's "Aloe")
# is a real photo with texture everywhere, as tests/test_data.hpp uses them.
GRAF1 = os.path.join(SAMPLES, "graf1.png")
GRAF3 = os.path.join(SAMPLES, "graf3.png")
PHOTO = os.path.join(SAMPLES, "aloeL.jpg")


def grey(path):
    image = cv2.imread(path, cv2.IMREAD_GRAYSCALE)
    assert image is not None, "missing test image " + path
    return image


def corner_distances(estimate, truth, shape):
    """The distances, pixels, between where `estimate` and `truth` (3x3 homographies) put the four
    corners of an image of `shape` (rows, columns)."""
    h, w = shape[:2]
    corners = np.array([[0, 0, 1], [w - 1, 0, 1], [0, h - 1, 1], [w - 1, h - 1, 1]], float).T
    a, b = estimate @ corners, truth @ corners
    return np.linalg.norm(a[:2] / a[2] - b[:2] / b[2], axis=0)


def graf_homography_1to3():
    storage = cv2.FileStorage(os.path.join(SAMPLES, "H1to3p.xml"), cv2.FILE_STORAGE_READ)
    return storage.getNode("H13").mat()


def cpp_features(path, features, max_tilt, descriptor, threads):
    """Keypoints (N x 7: x y size angle response octave view) and descriptors of the C++ extractor."""
    out = subprocess.run([PROBE, path, str(features), repr(max_tilt), descriptor, str(threads)], check=True,
                         capture_output=True, text=True).stdout.split("\n")
    rows = [line.split() for line in out if line]
    numbers = np.array([[float(v) for v in r[:7]] for r in rows])
    descriptors = np.array([bytearray.fromhex(r[7]) for r in rows], dtype=np.uint8)
    return numbers, descriptors


@pytest.mark.skipif(PROBE is None, reason="needs the C++ probe (run through ctest)")
@pytest.mark.parametrize("descriptor,max_tilt,threads", [("rbrief", 1.0, 1), ("rbrief", 2.83, 2), ("brisk", 2.83, 1)])
def test_equals_the_cpp_extractor(descriptor, max_tilt, threads):
    path = PHOTO
    numbers, want = cpp_features(path, 700, max_tilt, descriptor, threads)
    extractor = affine_orb.Extractor(features=700, max_tilt=max_tilt, descriptor=descriptor, threads=threads)
    keypoints, descriptors, views = extractor.extract(cv2.imread(path, cv2.IMREAD_GRAYSCALE))
    assert len(keypoints) == len(numbers) > 700 * (1 if max_tilt == 1.0 else 2) - 5
    got = np.array([[k.pt[0], k.pt[1], k.size, k.angle, k.response, k.octave, v] for k, v in zip(keypoints, views)])
    # cv2.KeyPoint stores float32, the probe prints 9 significant digits: exact.
    assert np.array_equal(got.astype(np.float32), numbers.astype(np.float32))
    assert descriptors.dtype == np.uint8 and descriptors.shape == (len(keypoints), 32 if descriptor == "rbrief" else 64)
    assert np.array_equal(descriptors, want)


def cpp_match(path1, path2, features, min_inliers):
    """The C++ TwoViewMatcher's result: stage, verified, both images' keypoint rows and descriptors,
    and the matches (query, train, distance, inlier)."""
    out = subprocess.run([PROBE, "--match", path1, path2, str(features), str(min_inliers)], check=True,
                         capture_output=True, text=True).stdout.split("\n")
    stage, verified = int(out[0].split()[1]), out[0].split()[3] == "1"
    blocks, current = [], []
    for line in out[1:]:
        if line == "--":
            blocks.append(current)
            current = []
        elif line:
            current.append(line.split())
    blocks.append(current)

    def features(rows):
        return (np.array([[float(v) for v in r[:7]] for r in rows]),
                np.array([bytearray.fromhex(r[7]) for r in rows], dtype=np.uint8))

    matches = np.array([[int(v) for v in r] for r in blocks[2]])
    return stage, verified, features(blocks[0]), features(blocks[1]), matches


def assert_equals_cpp_match(r, cpp):
    """Asserts that match_images()'s or TwoViewMatcher.match()'s dict `r` holds cpp_match()'s stage,
    keypoints, descriptors, matches and inlier flags; returns the stage."""
    stage, verified, (numbers1, want1), (numbers2, want2), matches = cpp
    assert (r["stage"], r["verified"]) == (stage, verified)
    assert len(r["stages"]) == stage + 1
    for keypoints, views, descriptors, numbers, want in ((r["keypoints1"], r["views1"], r["descriptors1"], numbers1, want1),
                                                         (r["keypoints2"], r["views2"], r["descriptors2"], numbers2, want2)):
        got = np.array([[k.pt[0], k.pt[1], k.size, k.angle, k.response, k.octave, v] for k, v in zip(keypoints, views)])
        assert np.array_equal(got.astype(np.float32), numbers.astype(np.float32))
        assert np.array_equal(descriptors, want)
    got = np.array([[m.queryIdx, m.trainIdx, int(m.distance), int(i)] for m, i in zip(r["matches"], r["inliers"])])
    assert np.array_equal(got, matches)
    return stage


@pytest.mark.skipif(PROBE is None, reason="needs the C++ probe (run through ctest)")
@pytest.mark.parametrize("pair,min_inliers", [(3, 15), pytest.param(5, 15, marks=pytest.mark.data), (3, 1000)])
def test_match_images_equals_the_cpp_matcher(pair, min_inliers):
    """match_images() gives the C++ TwoViewMatcher's stage, keypoints, descriptors, matches and inlier
    flags: on graf 1->3 (verified at stage 0), 1->5 (escalates to the views) and 1->3 with an
    unreachable min_inliers (every stage runs)."""
    path1 = GRAF1
    path2 = GRAF3 if pair == 3 else os.path.join(DATA, "oxford", "graf", "img%d.png" % pair)
    r = affine_orb.match_images(cv2.imread(path1, cv2.IMREAD_GRAYSCALE), cv2.imread(path2, cv2.IMREAD_GRAYSCALE),
                                features=1000, min_inliers=min_inliers)
    stage = assert_equals_cpp_match(r, cpp_match(path1, path2, 1000, min_inliers))
    if min_inliers == 1000:
        assert stage == len(r["stages"]) - 1 == 2 and not r["verified"]
        assert [s["failure"] for s in r["stages"]] == ["few inliers"] * 3
    else:
        assert r["verified"] and r["stages"][-1]["failure"] is None
    assert r["model"] in ("homography", "fundamental")
    assert r["homography"].shape == (3, 3)


@pytest.mark.skipif(PROBE is None, reason="needs the C++ probe (run through ctest)")
def test_two_view_matcher_reused_on_pairs_of_other_sizes_equals_the_cpp_matcher():
    """One TwoViewMatcher, which keeps its buffers from call to call, on graf 1->3, then a pair whose
    image 1 is another photo of another size, then graf 1->3 again: each result is a fresh C++
    TwoViewMatcher's on that pair."""
    matcher = affine_orb.TwoViewMatcher(features=1000, min_inliers=15)
    assert matcher.descriptor_size == 32 and grey(PHOTO).shape != grey(GRAF1).shape
    for path1, path2 in ((GRAF1, GRAF3), (PHOTO, GRAF3), (GRAF1, GRAF3)):
        r = matcher.match(grey(path1), grey(path2))
        assert_equals_cpp_match(r, cpp_match(path1, path2, 1000, 15))


def test_two_view_matcher_from_several_threads_gives_the_serial_results():
    """Calls on one TwoViewMatcher from three Python threads at once take turns: each gets what
    match_images() gives for its pair."""
    pairs = [(grey(GRAF1), grey(GRAF3)), (grey(PHOTO), grey(GRAF3)), (grey(GRAF3), grey(GRAF1))]
    want = [affine_orb.match_images(a, b, features=600) for a, b in pairs]
    matcher = affine_orb.TwoViewMatcher(features=600)
    got = [None] * len(pairs)

    def work(i):
        got[i] = matcher.match(*pairs[i])

    workers = [threading.Thread(target=work, args=(i,)) for i in range(len(pairs))]
    for w in workers:
        w.start()
    for w in workers:
        w.join()
    for r, w in zip(got, want):
        assert [(m.queryIdx, m.trainIdx) for m in r["matches"]] == [(m.queryIdx, m.trainIdx) for m in w["matches"]]
        assert np.array_equal(r["descriptors1"], w["descriptors1"]) and np.array_equal(r["inliers"], w["inliers"])
        assert np.array_equal(r["homography"], w["homography"])


def test_two_view_matcher_refuses_bad_input():
    image = np.zeros((64, 64), np.uint8)
    with pytest.raises(ValueError):
        affine_orb.TwoViewMatcher(descriptor="sift")
    with pytest.raises(ValueError):
        affine_orb.TwoViewMatcher(min_inliers=3)
    matcher = affine_orb.TwoViewMatcher(descriptor="brisk")
    assert matcher.descriptor_size == 64
    with pytest.raises(TypeError):
        matcher.match(image.astype(np.float32), image)
    with pytest.raises(ValueError):
        matcher.match(image, image, mask2=np.zeros((3, 3), np.uint8))
    r = matcher.match(image, image)  # a flat image: no keypoints, documented empty result
    assert not r["verified"] and r["matches"] == [] and r["model"] == "none"


@pytest.mark.data
def test_match_images_guided_matching_and_precision_test_are_reported():
    """guided_rounds and max_half_disagreement reach the C++ options: graf 1->2 is verified at stage
    0 by a homography refined by the default rounds (none with guided_rounds=0), and the precision
    test, on by default, measures the half disagreement (about a pixel on this easy pair; None with
    max_half_disagreement=None), whose ground-truth homography the refined model matches at image 1's
    corners."""
    image1 = cv2.imread(os.path.join(DATA, "oxford", "graf", "img1.png"), cv2.IMREAD_GRAYSCALE)
    image2 = cv2.imread(os.path.join(DATA, "oxford", "graf", "img2.png"), cv2.IMREAD_GRAYSCALE)
    truth = np.loadtxt(os.path.join(DATA, "oxford", "graf", "H1to2p"))
    plain = affine_orb.match_images(image1, image2, guided_rounds=0, max_half_disagreement=None)
    assert plain["verified"] and plain["stages"][0]["guided_rounds"] == 0
    assert plain["stages"][0]["half_disagreement"] is None
    r = affine_orb.match_images(image1, image2, max_half_disagreement=5.0)
    assert r["verified"] and r["stage"] == 0 and r["model"] == "homography"
    assert r["stages"][0]["guided_rounds"] > 0
    assert 0.0 <= r["stages"][0]["half_disagreement"] < 5.0
    strict = affine_orb.match_images(image1, image2, max_half_disagreement=1e-3, stages=[])
    assert not strict["verified"] and strict["stages"][0]["failure"] == "imprecise"
    assert strict["stages"][0]["half_disagreement"] > 1e-3
    assert corner_distances(r["homography"], truth, image1.shape).max() < 2.0


@pytest.mark.data
def test_match_images_last_stage_search_finds_bark_1_to_6s_plane():
    """last_stage_search and min_inliers reach the C++ options. At 15 inliers bark 1->6 ends
    unverified either way, with a homography hundreds of pixels off without the last stage's search
    and within 10 px of the ground truth (corners) with it; the defaults (12 inliers) verify it at
    stage 1 within 3 px."""
    image1 = cv2.imread(os.path.join(DATA, "oxford", "bark", "img1.png"), cv2.IMREAD_GRAYSCALE)
    image6 = cv2.imread(os.path.join(DATA, "oxford", "bark", "img6.png"), cv2.IMREAD_GRAYSCALE)
    truth = np.loadtxt(os.path.join(DATA, "oxford", "bark", "H1to6p"))
    def corner_error(estimate):
        return corner_distances(estimate, truth, image1.shape).mean()

    plain = affine_orb.match_images(image1, image6, min_inliers=15, last_stage_search=False)
    searched = affine_orb.match_images(image1, image6, min_inliers=15)
    assert not plain["verified"] and not searched["verified"]
    assert corner_error(plain["homography"]) > 50.0
    assert searched["model"] == "homography" and corner_error(searched["homography"]) < 10.0
    assert searched["stages"][-1]["last_stage_search"] and not plain["stages"][-1]["last_stage_search"]
    default = affine_orb.match_images(image1, image6)
    assert default["verified"] and default["stage"] == 1 and corner_error(default["homography"]) < 3.0


@pytest.mark.data
def test_match_images_support_test_final_fit_and_progressive_sampling_reach_the_matcher():
    """max_false_alarms, min_inlier_ratio, final_fit and progressive_sampling reach the C++ options: on
    graf 1->2 the stage reports the chosen homography's log10 number of false alarms (far below 0;
    None without the test); an unreachable min_inlier_ratio leaves the pair unverified; the final fit
    (on by default) changes the homography, keeps the matches' count at least that of the stage's own
    matches, and flags as inliers exactly the matches within 4 px both ways; PROSAC verifies the
    pair too."""
    image1 = cv2.imread(os.path.join(DATA, "oxford", "graf", "img1.png"), cv2.IMREAD_GRAYSCALE)
    image2 = cv2.imread(os.path.join(DATA, "oxford", "graf", "img2.png"), cv2.IMREAD_GRAYSCALE)
    r = affine_orb.match_images(image1, image2)
    assert r["verified"] and r["stage"] == 0
    assert r["stages"][0]["log10_false_alarms"] < -100
    assert affine_orb.match_images(image1, image2, max_false_alarms=None)["stages"][0]["log10_false_alarms"] is None
    ratio = affine_orb.match_images(image1, image2, min_inlier_ratio=1.0, stages=[])
    assert not ratio["verified"] and ratio["stages"][0]["failure"] == "inlier ratio"
    unfitted = affine_orb.match_images(image1, image2, final_fit=False)
    assert unfitted["verified"] and not np.allclose(unfitted["homography"], r["homography"])
    h = r["homography"]
    p1 = np.array([[*r["keypoints1"][m.queryIdx].pt, 1.0] for m in r["matches"]]).T
    p2 = np.array([[*r["keypoints2"][m.trainIdx].pt, 1.0] for m in r["matches"]]).T
    forward = h @ p1
    backward = np.linalg.inv(h) @ p2
    within = (np.linalg.norm(forward[:2] / forward[2] - p2[:2], axis=0) <= 4.0) & (
        np.linalg.norm(backward[:2] / backward[2] - p1[:2], axis=0) <= 4.0)
    assert np.array_equal(np.asarray(r["inliers"], bool), within)
    assert affine_orb.match_images(image1, image2, progressive_sampling=True)["verified"]
    with pytest.raises(ValueError):
        affine_orb.match_images(image1, image2, max_false_alarms=0.0)


@pytest.mark.data
def test_match_images_align_correspondences_aligns_image_2_points():
    """align_correspondences reaches the C++ option: without it points2 are the train keypoints' positions; with it
    the inliers' image-2 points lie closer to where the ground truth maps their image-1 keypoints."""
    image1 = cv2.imread(os.path.join(DATA, "oxford", "boat", "img1.png"), cv2.IMREAD_GRAYSCALE)
    image2 = cv2.imread(os.path.join(DATA, "oxford", "boat", "img3.png"), cv2.IMREAD_GRAYSCALE)
    truth = np.loadtxt(os.path.join(DATA, "oxford", "boat", "H1to3p"))

    def mean_error(r):
        keep = [(m.queryIdx, i) for i, (m, inlier) in enumerate(zip(r["matches"], r["inliers"])) if inlier]
        p1 = np.array([[*r["keypoints1"][q].pt, 1.0] for q, _ in keep]).T
        mapped = truth @ p1
        mapped = (mapped[:2] / mapped[2]).T
        return np.linalg.norm(r["points2"][[i for _, i in keep]] - mapped, axis=1).mean()

    plain = affine_orb.match_images(image1, image2)
    assert plain["verified"] and plain["points2"].shape == (len(plain["matches"]), 2)
    assert plain["stages"][-1]["aligned"] == 0
    positions = np.array([plain["keypoints2"][m.trainIdx].pt for m in plain["matches"]], np.float32)
    assert np.array_equal(plain["points2"], positions)
    aligned = affine_orb.match_images(image1, image2, align_correspondences=True)
    assert aligned["verified"] and aligned["stages"][-1]["aligned"] > 0
    assert mean_error(aligned) < mean_error(plain)


def test_match_images_stages_follow_max_tilt():
    """stages=None gives the stages up to max_tilt (affine_orb::stages_up_to): with an unreachable
    min_inliers every stage runs, 2 with the default 2.83, 4 with 5.66 (tilts 4 and 5.66 added), 1
    with 2; explicit stages are taken as given."""
    image1, image2 = grey(GRAF1), grey(GRAF3)
    for max_tilt, tilts in ((2.83, [1.0, 2.0, 2.83]), (5.66, [1.0, 2.0, 2.83, 4.0, 5.66]), (2.0, [1.0, 2.0])):
        r = affine_orb.match_images(image1, image2, features=300, max_tilt=max_tilt, min_inliers=100000)
        assert not r["verified"]
        assert [round(s["max_tilt"], 2) for s in r["stages"]] == tilts
    r = affine_orb.match_images(image1, image2, features=300, max_tilt=5.66, stages=[(4.0, 1.0)], min_inliers=100000)
    assert [round(s["max_tilt"], 2) for s in r["stages"]] == [1.0, 4.0]


def test_match_images_refuses_bad_input():
    image = np.zeros((64, 64), np.uint8)
    with pytest.raises(ValueError):
        affine_orb.match_images(image, image, stages=[(2.0, 0.5), (2.0, 0.5)])  # tilts not increasing
    with pytest.raises(ValueError):
        affine_orb.match_images(image, image, min_inliers=3)
    with pytest.raises(ValueError):
        affine_orb.match_images(image, image, descriptor="sift")
    with pytest.raises(TypeError):
        affine_orb.match_images(image.astype(np.float32), image)
    with pytest.raises(ValueError):
        affine_orb.match_images(image, image, mask1=np.zeros((3, 3), np.uint8))
    with pytest.raises(ValueError):
        affine_orb.match_images(image, image, guided_rounds=-1)
    with pytest.raises(ValueError):
        affine_orb.match_images(image, image, max_half_disagreement=-1.0)
    with pytest.raises(ValueError):
        affine_orb.match_images(image, image, max_half_disagreement=0.0)
    with pytest.raises(TypeError):
        affine_orb.match_images(image, image, align_correspondences="yes")
    r = affine_orb.match_images(image, image)  # a flat image: no keypoints, documented empty result
    assert not r["verified"] and r["matches"] == [] and r["model"] == "none"
    assert r["points2"].shape == (0, 2)


def test_version_is_the_headers_and_cmakes():
    """__version__ is the string of include/affine_orb/version.hpp and the version CMake configured
    (AFFINE_ORB_EXPECTED_VERSION, set by ctest)."""
    header = open(os.path.join(os.path.dirname(__file__), "../../include/affine_orb/version.hpp")).read()
    parts = [re.search(r"^#define AFFINE_ORB_VERSION_%s (\d+)$" % p, header, re.M).group(1)
             for p in ("MAJOR", "MINOR", "PATCH")]
    assert affine_orb.__version__ == ".".join(parts)
    expected = os.environ.get("AFFINE_ORB_EXPECTED_VERSION")
    if expected is not None:
        assert affine_orb.__version__ == expected


def test_the_module_is_the_one_on_pythonpath():
    """The module under test is the build tree's (ctest sets PYTHONPATH to it), not an installed copy
    such as the Debian package's in /usr/lib/python3/dist-packages."""
    path = os.environ.get("PYTHONPATH")
    if path:
        assert os.path.dirname(os.path.realpath(affine_orb.__file__)) == os.path.realpath(path.split(os.pathsep)[0])


def test_views_and_defaults():
    image = grey(GRAF1)
    extractor = affine_orb.Extractor()
    keypoints, descriptors, views = extractor.extract(image)
    # The additive budget: 1000 from the image (view 0), 1000 from the 17 tilted views.
    assert extractor.features == 1000 and len(keypoints) == 2000
    assert np.count_nonzero(views == 0) == 1000 and len(set(views.tolist())) >= 15
    plain_keypoints, plain_descriptors = affine_orb.Extractor(max_tilt=1.0).detect_and_compute(image)
    assert np.array_equal(descriptors[views == 0], plain_descriptors)


def orb_level_budgets(total, scale_factor, levels):
    """ORB-SLAM's split of a budget over the pyramid: level l gets round(N (1 - f) / (1 - f^L) f^l)
    with f = 1 / scale_factor, the last level the remainder."""
    f = 1.0 / scale_factor
    per_level = total * (1.0 - f) / (1.0 - f ** levels)
    budgets = []
    for _ in range(levels - 1):
        budgets.append(min(int(np.floor(per_level + 0.5)), total - sum(budgets)))
        per_level *= f
    return budgets + [total - sum(budgets)]


def test_carry_shortfalls_false_keeps_each_level_within_its_share():
    """A small image with a large budget runs short of corners at the coarse levels. By default the
    shortfall passes to the other levels (mostly level 0) and the budget is met; with
    carry_shortfalls=False each level keeps min(its share, what it has), and the levels that had no
    more than their share keep the very same keypoints."""
    image = cv2.resize(grey(PHOTO), (320, 256), interpolation=cv2.INTER_AREA)
    carrying = affine_orb.Extractor(features=3000, max_tilt=1.0)
    capped = affine_orb.Extractor(features=3000, max_tilt=1.0, carry_shortfalls=False)
    assert carrying.carry_shortfalls and not capped.carry_shortfalls
    with_kps, with_desc = carrying.detect_and_compute(image)
    without_kps, without_desc = capped.detect_and_compute(image)
    assert len(with_kps) == 3000 and len(without_kps) < 3000
    budgets = orb_level_budgets(3000, 1.2, 8)
    short = 0
    for level, budget in enumerate(budgets):
        with_level = [i for i, k in enumerate(with_kps) if k.octave == level]
        without_level = [i for i, k in enumerate(without_kps) if k.octave == level]
        assert len(without_level) == min(budget, len(with_level)), level
        short += len(without_level) < budget
        if len(without_level) == len(with_level):
            assert [with_kps[i].pt for i in with_level] == [without_kps[i].pt for i in without_level]
            assert np.array_equal(with_desc[with_level], without_desc[without_level])
    assert short > 0 and sum(k.octave == 0 for k in with_kps) > budgets[0]


def test_subpixel_positions_move_only_the_points():
    """The default puts level-0 keypoints on whole pixels (as ORB); subpixel=True moves them by at
    most half a pixel and keeps every descriptor."""
    image = grey(PHOTO)
    whole, d_whole = affine_orb.Extractor(max_tilt=1.0).detect_and_compute(image)
    shifted, d_shifted = affine_orb.Extractor(max_tilt=1.0, subpixel=True).detect_and_compute(image)
    level0 = [(a, b) for a, b in zip(whole, shifted) if a.octave == 0]
    assert len(whole) == len(shifted) and len(level0) > 100
    assert all(a.pt[0] == round(a.pt[0]) and a.pt[1] == round(a.pt[1]) for a, _ in level0)
    assert all(abs(a.pt[0] - b.pt[0]) <= 0.5 and abs(a.pt[1] - b.pt[1]) <= 0.5 for a, b in level0)
    assert sum(a.pt != b.pt for a, b in level0) > len(level0) // 2
    assert np.array_equal(d_whole, d_shifted)


def test_any_strides_and_roi():
    image = grey(PHOTO)
    extractor = affine_orb.Extractor(features=500, max_tilt=1.0)
    for view in (image[40:400, 30:500], image[::2, ::2], image[:, ::-1], np.asfortranarray(image)):
        k1, d1 = extractor.detect_and_compute(view)
        k2, d2 = extractor.detect_and_compute(np.ascontiguousarray(view))
        assert [k.pt for k in k1] == [k.pt for k in k2]
        assert np.array_equal(d1, d2)


def test_threads_give_identical_output_and_run_concurrently():
    image = grey(PHOTO)
    reference = affine_orb.Extractor(features=600, threads=1).extract(image)
    for threads in (2, 3):
        other = affine_orb.Extractor(features=600, threads=threads).extract(image)
        assert [k.pt for k in other[0]] == [k.pt for k in reference[0]]
        assert np.array_equal(other[1], reference[1]) and np.array_equal(other[2], reference[2])
    # Two Python threads with one Extractor each (the GIL is released while they work), then three
    # sharing one Extractor, whose calls take turns.
    shared = affine_orb.Extractor(features=600)
    results = [None] * 5

    def work(i):
        results[i] = (affine_orb.Extractor(features=600) if i < 2 else shared).extract(image)

    workers = [threading.Thread(target=work, args=(i,)) for i in range(5)]
    for w in workers:
        w.start()
    for w in workers:
        w.join()
    for r in results:
        assert np.array_equal(r[1], reference[1]) and np.array_equal(r[2], reference[2])


def test_cv2_interop_and_matching_graf():
    a, b = grey(GRAF1), grey(GRAF3)
    extractor = affine_orb.Extractor(spreading="strongest")
    ka, da = extractor.detect_and_compute(a)
    kb, db = extractor.detect_and_compute(b)
    # cv2.BFMatcher on the descriptors, and our matcher: the same nearest neighbours.
    knn = cv2.BFMatcher(cv2.NORM_HAMMING).knnMatch(da, db, k=2)
    ours = affine_orb.match(da, db, ratio=0.8)
    # The ratio is a float (MatcherOptions::ratio), compared exactly: d1 < float(0.8) * d2.
    ratio = float(np.float32(0.8))
    by_cv2 = {m.queryIdx: m for m, n in knn if m.distance < ratio * n.distance}
    assert {m.queryIdx for m in ours} == set(by_cv2)
    assert all(by_cv2[m.queryIdx].distance == m.distance for m in ours)
    drawn = cv2.drawKeypoints(a, ka, None)
    assert drawn.shape == a.shape + (3,)
    cv2.drawMatches(a, ka, b, kb, ours[:50], None)
    # Model selection on the matches: the homography agrees with the ground truth at the corners.
    p1 = np.array([ka[m.queryIdx].pt for m in ours])
    p2 = np.array([kb[m.trainIdx].pt for m in ours])
    result = affine_orb.select_model(p1, p2)
    assert result["success"] and result["homography"] is not None
    assert result["homography_inliers"].dtype == bool and len(result["homography_inliers"]) == len(ours)
    truth = graf_homography_1to3()
    # The image corners: extrapolated beyond most matches (800 x 640 image).
    assert corner_distances(result["homography"], truth, a.shape).max() < 10.0
    # The default rule (plane and parallax) finds no parallax beyond chance on this plane; every rule
    # is selectable, with or without the keypoints' octaves.
    assert result["model"] == "homography"
    assert result["parallax_significance"] <= 3.8
    octaves1 = [ka[m.queryIdx].octave for m in ours]
    octaves2 = [kb[m.trainIdx].octave for m in ours]
    for rule in ("plane_parallax", "score_ratio", "gric", "inlier_ratio"):
        chosen = affine_orb.select_model(p1, p2, rule=rule, octaves1=octaves1, octaves2=octaves2)
        assert chosen["success"] and chosen["model"] in ("homography", "fundamental")
        assert chosen["homography"] is not None and chosen["fundamental"] is not None
    with pytest.raises(ValueError, match="rule"):
        affine_orb.select_model(p1, p2, rule="ransac")
    with pytest.raises(ValueError, match="together"):
        affine_orb.select_model(p1, p2, octaves1=octaves1)
    with pytest.raises(ValueError, match="octaves"):
        affine_orb.select_model(p1, p2, octaves1=octaves1[1:], octaves2=octaves2)


def test_bad_input():
    extractor = affine_orb.Extractor()
    with pytest.raises(TypeError, match="uint8"):
        extractor.detect_and_compute(np.zeros((40, 40), np.float32))
    with pytest.raises(TypeError, match="numpy array"):
        extractor.detect_and_compute([[1, 2], [3, 4]])
    with pytest.raises(ValueError, match="2-D"):
        extractor.detect_and_compute(np.zeros((40, 40, 3), np.uint8))
    with pytest.raises(ValueError, match="empty"):
        extractor.detect_and_compute(np.zeros((0, 40), np.uint8))
    with pytest.raises(ValueError, match="mask"):
        extractor.detect_and_compute(np.zeros((40, 40), np.uint8), np.zeros((20, 40), np.uint8))
    with pytest.raises(ValueError, match="descriptor"):
        affine_orb.Extractor(descriptor="sift")
    with pytest.raises(ValueError, match="features"):
        affine_orb.Extractor(features=0)
    with pytest.raises(ValueError, match="max_tilt"):
        affine_orb.Extractor(max_tilt=0.5)
    with pytest.raises(ValueError, match="ratio"):
        affine_orb.match(np.zeros((3, 32), np.uint8), np.zeros((3, 32), np.uint8), ratio=0.0)
    with pytest.raises(ValueError):
        affine_orb.match(np.zeros((3, 32), np.uint8), np.zeros((3, 64), np.uint8))
    with pytest.raises(ValueError, match="N x 2"):
        affine_orb.select_model(np.zeros((10, 3)), np.zeros((10, 3)))
    with pytest.raises(ValueError):
        affine_orb.select_model(np.full((10, 2), np.nan), np.zeros((10, 2)))
    # A flat image: nothing found, an empty 0 x 32 array.
    keypoints, descriptors = extractor.detect_and_compute(np.full((64, 64), 9, np.uint8))
    assert keypoints == [] and descriptors.shape == (0, 32)
