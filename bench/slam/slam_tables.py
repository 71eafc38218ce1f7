#!/usr/bin/python3
"""slam_tables.py -- the ORB-SLAM tables of docs/slam.md, from runs made with
../shared/slam/run.sh (rendered sequences) and bench/slam/kitti_runs.sh (KITTI 00).

  slam_tables.py relocalisation RUNS SEQS CONF...   revisit_sweep* sequences, RGB-D
  slam_tables.py monocular RUNS_CSV CONF...          mono rows of ../shared/slam/analyze.py's runs.csv
  slam_tables.py rgbd RUNS_CSV CONF...               RGB-D rows of the same
  slam_tables.py kitti RUNS GROUNDTRUTH CONF...      KITTI 00 monocular runs
  slam_tables.py suite RUNS SEQS CONF...             bench/slam/suite.sh's tables (the first CONF is stock)
  slam_tables.py atlas RUNS CONF...                  ORB-SLAM3: what became of each run's first map
  slam_tables.py span RUNS SEQS CONF...              monocular maps judged on the frames every map covers

Every cell is the median (min–max) over a configuration's runs. Needs ../shared/slam/ate.py (found
beside this project, or through SLAM_HARNESS) and numpy; use /usr/bin/python3 on Debian.

relocalisation: per run, the first frame after the cut (part "B" of the sequence's obliquity.txt)
  whose pose, after an SE(3) alignment of the part-A poses to the ground truth, lies within
  kCorrectM of it; its axis obliquity (degrees from the wall's normal: steeper = the relocaliser
  coped with a larger viewpoint change), the frames with a pose, the correct part-B poses, and the
  median and mean tracking times the example prints (ms).
monocular: per sequence, the runs whose keyframe map is correct (Sim(3) ATE <= kCorrectMapM over at
  least kCoverage of the frames), then ATE and coverage of all runs.
rgbd: per sequence, frames with a pose, ATE (SE(3), every pose), median and mean tracking time, and
  the median of the mean tracking time against the first configuration's.
suite: one table per sequence type (SEQS/TYPE_sSEED, every seed pooled) and mode from RUNS/runs.csv
  (../shared/slam/analyze.py): keyframes, the frame of the second keyframe (RGB-D ORB-SLAM2 takes
  it only once fewer than 40 % of the first keyframe's points are tracked), runs with a reset, runs that relocalise and the obliquity
  there (revisit_sweep, RGB-D, as `relocalisation`), correct maps (monocular, as `monocular`), ATE,
  mean tracking time against stock's; RUNS/kitti as `kitti`; then every sequence and mode where a
  configuration is worse than stock beyond the run-to-run range: all of its runs worse than all of
  stock's in a metric (fewer keyframes, frames with a pose, relocalisations or correct maps, more
  resets, a larger ATE), judged where both have at least kMinRuns runs.
atlas: ORB-SLAM3 runs (RUNS/CONF/SEQUENCE/MODE_I/log.txt), per sequence and mode, then pooled over
  the seeds of each sequence type: the keyframes the first map made before tracking was lost (the
  keyframe id the next map starts at), and what ORB-SLAM3 did with it: dropped it (a map of at most
  10 keyframes is reset at once), kept it in its atlas and started a new map, or tracked on (no
  loss, or relocalised within the 3 s it tries); then the runs where a later map merged with an
  earlier one.
span: monocular runs of rendered sequences (RUNS/CONF/SEQUENCE/mono_I/KeyFrameTrajectory.txt, the last
  map), per sequence, then pooled over the seeds of each sequence type: the span every run's map covers
  (from the latest first keyframe to the earliest last keyframe over the runs of every CONF that have
  a map of >= 3 keyframes), then per configuration the Sim(3) ATE of the whole map, the Sim(3) ATE of
  its keyframes inside the span alone, the runs correct there (<= kCorrectMapM), and the map's scale
  drift: the largest over the smallest Sim(3) scale of windows of kDriftWindow consecutive keyframes
  (1 for a map whose scale holds; a monocular map can drift where its motion leaves the scale
  weakly observed). A map that starts earlier than another is judged by `suite` on frames the other
  never maps; this compares the two where both exist.
kitti: the runs whose map starts (>= 3 keyframes), when the first keyframe was taken (s from the
  first frame), keyframes, Sim(3) ATE of the keyframes (m), mean tracking time (ms).
"""
import csv
import glob
import os
import re
import statistics
import sys

import numpy as np

HARNESS = os.environ.get("SLAM_HARNESS",
                         os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "shared", "slam"))
sys.path.insert(0, HARNESS)
import ate  # noqa: E402  (../shared/slam/ate.py)

kCorrectM = 0.10      # a relocalised pose counts when within 10 cm of the ground truth
kCorrectMapM = 0.10   # a monocular map counts as correct with Sim(3) ATE <= 10 cm ...
kCoverage = 0.50      # ... over at least half of the sequence's frames
kDriftWindow = 12     # span: keyframes per window of the scale-drift measure (about 2 s of monocular `shake`)
kMinRuns = 2          # suite: runs per side below which a sequence has no run-to-run range to judge by
# ORB-SLAM3 prints no "System Reseting" at its default verbosity; this line of its local mapping
# marks the same event, a map dropped (one of at most 10 keyframes lost, or a failed initialisation).
kOrbSlam3Reset = "LM: Active map reset recieved"


def cell(values, fmt="%.1f"):
    values = [v for v in values if v is not None]
    if not values:
        return "–"
    return (fmt + " (" + fmt + "–" + fmt + ")") % (statistics.median(values), min(values), max(values))


def tracking_times(log):
    """(median, mean) tracking time in ms that rgbd_tum/mono_tum/mono_kitti print, or None."""
    med = re.findall(r"median tracking time: ([0-9.e+-]+)", log)
    mean = re.findall(r"mean tracking time: ([0-9.e+-]+)", log)
    return (float(med[-1]) * 1e3 if med else None, float(mean[-1]) * 1e3 if mean else None)


def read_log(directory):
    for name in ("log.txt", "out.log"):
        path = os.path.join(directory, name)
        if os.path.exists(path):
            return open(path, errors="replace").read()
    return ""


def revisit_side(seqs, seq):
    """(stamps, parts, obliquities, ground-truth times, ground-truth poses) of a revisit sequence, or None."""
    side = os.path.join(seqs, seq, "obliquity.txt")
    if not os.path.exists(side):
        return None
    rows = [l.split() for l in open(side) if l.strip() and not l.startswith("#")]
    t_gt, p_gt = ate.read_tum(os.path.join(seqs, seq, "groundtruth.txt"))
    return (np.array([float(r[1]) for r in rows]), [r[2] for r in rows], [float(r[4]) for r in rows], t_gt, p_gt)


def relocalised_at(directory, side):
    """(obliquity of the first correct pose after the cut or None, frames with a pose, correct poses after it)."""
    stamps, part, obliquity, t_gt, p_gt = side
    trajectory = os.path.join(directory, "CameraTrajectory.txt")
    if not os.path.exists(trajectory):
        return None, 0, 0
    t_e, p_e = ate.read_tum(trajectory)
    ie, ig = ate.associate(t_e, t_gt)
    frame = [int(np.argmin(np.abs(stamps - t_e[i]))) for i in ie]
    in_a = [k for k, f in enumerate(frame) if part[f] == "A"]
    if len(in_a) < 3:
        return None, len(t_e), 0
    s, R, t = ate.umeyama(p_e[ie[in_a], :3], p_gt[ig[in_a], :3])
    first, correct = None, 0
    for k, f in enumerate(frame):
        if part[f] != "B":
            continue
        if np.linalg.norm(s * R @ p_e[ie[k], :3] + t - p_gt[ig[k], :3]) < kCorrectM:
            correct += 1
            if first is None:
                first = obliquity[f]
    return first, len(t_e), correct


def relocalisation(runs, seqs, confs):
    print("| sequence | configuration | relocalised | obliquity at the first pose after the cut, ° | frames with a pose "
          "| correct poses after the cut | tracking ms, median | tracking ms, mean |")
    print("|---|---|---|---|---|---|---|---|")
    for seq in sorted(os.listdir(seqs)):
        side = revisit_side(seqs, seq) if seq.startswith("revisit_sweep") else None
        if side is None:
            continue
        for conf in confs:
            results = []
            for d in sorted(glob.glob(os.path.join(runs, conf, seq, "rgbd_*"))):
                median_ms, mean_ms = tracking_times(read_log(d))
                results.append(relocalised_at(d, side) + (median_ms, mean_ms))
            if not results:
                continue
            print("| %s | %s | %d/%d | %s | %s | %s | %s | %s |" % (
                seq, conf, sum(r[0] is not None for r in results), len(results), cell([r[0] for r in results]),
                cell([r[1] for r in results], "%.0f"), cell([r[2] for r in results], "%.0f"),
                cell([r[3] for r in results]), cell([r[4] for r in results])))


def monocular(runs_csv, confs):
    rows = [r for r in csv.DictReader(open(runs_csv)) if r["mode"] == "mono"]
    number = lambda v: float(v) if v not in ("", "None", None) else None
    print("| sequence | configuration | correct maps (ATE <= %.2f m over >= %d %% of the frames) | map created at frame "
          "| coverage %% | ATE m | tracking ms, median | tracking ms, mean |" % (kCorrectMapM, kCoverage * 100))
    print("|---|---|---|---|---|---|---|---|")
    for seq in sorted({r["seq"] for r in rows}):
        for conf in confs:
            rs = [r for r in rows if r["seq"] == seq and r["conf"] == conf]
            if not rs:
                continue
            ates = [number(r["ate_rmse"]) for r in rs]  # mono: the keyframes, Sim(3)
            spans = [number(r["kf_span_frac"]) for r in rs]
            correct = sum(1 for a, s in zip(ates, spans) if a is not None and s is not None and a <= kCorrectMapM
                          and s >= kCoverage)
            print("| %s | %s | %d/%d | %s | %s | %s | %s | %s |" % (
                seq, conf, correct, len(rs), cell([number(r["kf_first_idx"]) for r in rs], "%.0f"),
                cell([s * 100 if s is not None else None for s in spans], "%.0f"), cell(ates, "%.3f"),
                cell([number(r["median_track_s"]) * 1e3 if number(r["median_track_s"]) else None for r in rs]),
                cell([number(r["mean_track_s"]) * 1e3 if number(r["mean_track_s"]) else None for r in rs])))


def rgbd(runs_csv, confs):
    rows = [r for r in csv.DictReader(open(runs_csv)) if r["mode"] == "rgbd"]
    number = lambda v: float(v) if v not in ("", "None", None) else None
    print("| sequence | configuration | frames with a pose | ATE m | tracking ms, median | tracking ms, mean "
          "| mean tracking time / %s's |" % confs[0])
    print("|---|---|---|---|---|---|---|")
    for seq in sorted({r["seq"] for r in rows}):
        base = [number(r["mean_track_s"]) for r in rows if r["seq"] == seq and r["conf"] == confs[0]]
        base = statistics.median([b for b in base if b]) if any(base) else None
        for conf in confs:
            rs = [r for r in rows if r["seq"] == seq and r["conf"] == conf]
            if not rs:
                continue
            means = [number(r["mean_track_s"]) for r in rs]
            ratio = "%.2f" % (statistics.median([m for m in means if m]) / base) if base and any(means) else "–"
            print("| %s | %s | %s | %s | %s | %s | %s |" % (
                seq, conf, cell([number(r["poses"]) for r in rs], "%.0f"), cell([number(r["ate_rmse"]) for r in rs], "%.3f"),
                cell([number(r["median_track_s"]) * 1e3 if number(r["median_track_s"]) else None for r in rs]),
                cell([m * 1e3 if m else None for m in means]), ratio))


def keyframe_map(directory):
    """(timestamps, poses) of a run's KeyFrameTrajectory.txt (its last map), or None without a map of
    >= 3 keyframes."""
    path = os.path.join(directory, "KeyFrameTrajectory.txt")
    if not os.path.exists(path):
        return None
    t, p = ate.read_tum(path)
    return (t, p) if len(t) >= 3 else None


def kitti(runs, groundtruth, confs):
    t_gt, p_gt = ate.read_tum(groundtruth)
    print("| configuration | maps | first keyframe at s | keyframes | Sim(3) ATE m | tracking ms, mean |")
    print("|---|---|---|---|---|---|")
    for conf in confs:
        results = []
        for d in sorted(glob.glob(os.path.join(runs, conf, "kitti00", "mono_*"))):
            _, mean_ms = tracking_times(read_log(d))
            keyframes = keyframe_map(d)
            if keyframes is None:
                results.append((None, None, None, mean_ms))
                continue
            t, p = keyframes
            res, _ = ate.evaluate(t_gt, p_gt, t, p, sim3=True)
            results.append((t[0] - t_gt[0], len(t), res["ate"]["rmse"] if "ate" in res else None, mean_ms))
        if not results:
            continue
        maps = [r for r in results if r[0] is not None]
        print("| %s | %d/%d | %s | %s | %s | %s |" % (
            conf, len(maps), len(results), cell([r[0] for r in maps]), cell([r[1] for r in maps], "%.0f"),
            cell([r[2] for r in maps], "%.3f"), cell([r[3] for r in results])))


def sequence_type(seq):
    """'oblique' for SEQS/oblique_s3 (suite.sh's names), else the name itself."""
    base, _, seed = seq.rpartition("_s")
    return base if base and seed.isdigit() else seq


def sequence_seed(seq):
    """3 for oblique_s3 (suite.sh's names), else 0."""
    return int(seq.rpartition("_s")[2]) if sequence_type(seq) != seq else 0


# Metrics of the regression list: (runs.csv column or derived key, label, True when larger is better).
REGRESSION_METRICS = [("keyframes", "keyframes", True), ("poses", "frames with a pose", True),
                      ("reset", "runs with a reset", False), ("relocalised", "relocalises", True),
                      ("loop", "runs with a loop closure", True), ("correct", "correct map", True),
                      ("ate", "ATE m", False)]


def suite_rows(runs, seqs):
    """runs.csv's rows with derived per-run fields: reset (0/1: the fork dropped its map), loop (0/1: a loop closed),
    relocalised (0/1) and the obliquity (revisit_sweep RGB-D), correct (0/1, monocular), ate, track_ms."""
    number = lambda v: float(v) if v not in ("", "None", None) else None
    sides = {}
    rows = []
    for r in csv.DictReader(open(os.path.join(runs, "runs.csv"))):
        row = dict(r)
        row["type"] = sequence_type(r["seq"])
        row["keyframes"] = number(r["keyframes"])
        row["second"] = number(r["kf_second_idx"])
        row["poses"] = number(r["poses"]) if r["mode"] == "rgbd" else None
        log = read_log(os.path.join(runs, r["conf"], r["seq"], "%s_%s" % (r["mode"], r["run"])))
        row["reset"] = 1.0 if (number(r["msg_reset"]) or 0) > 0 or kOrbSlam3Reset in log else 0.0
        row["loop"] = 1.0 if (number(r["msg_loop"]) or 0) > 0 else 0.0
        row["ate"] = number(r["ate_rmse"])
        mean = number(r["mean_track_s"])
        row["track_ms"] = mean * 1e3 if mean else None
        row["relocalised"], row["obliquity"], row["correct"] = None, None, None
        if r["mode"] == "rgbd" and row["type"] == "revisit_sweep":
            if r["seq"] not in sides:
                sides[r["seq"]] = revisit_side(seqs, r["seq"])
            if sides[r["seq"]] is not None and "B" in sides[r["seq"]][1]:
                first = relocalised_at(os.path.join(runs, r["conf"], r["seq"], "rgbd_" + r["run"]), sides[r["seq"]])[0]
                row["relocalised"], row["obliquity"] = (0.0 if first is None else 1.0), first
        if r["mode"] == "mono":
            span = number(r["kf_span_frac"])
            row["correct"] = 1.0 if (row["ate"] is not None and span is not None and row["ate"] <= kCorrectMapM
                                     and span >= kCoverage) else 0.0
        rows.append(row)
    return rows


def count(rows, key):
    values = [r[key] for r in rows if r[key] is not None]
    return "%d/%d" % (sum(values), len(values)) if values else "–"


def suite(runs, seqs, confs):
    rows = suite_rows(runs, seqs)
    stock = confs[0]
    for kind in sorted({r["type"] for r in rows}):
        for mode in ("rgbd", "mono"):
            group = [r for r in rows if r["type"] == kind and r["mode"] == mode]
            if not group:
                continue
            seeds = sorted({r["seq"] for r in group})
            print("\n%s, %s: %d sequences (%s)\n" % (kind, "RGB-D" if mode == "rgbd" else "monocular", len(seeds),
                                                    " ".join(s.rpartition("_s")[2] for s in seeds)))
            print("| configuration | runs | keyframes | second keyframe at frame | runs with a reset | relocalised "
                  "| obliquity there, ° | runs with a loop closure | correct maps | ATE m | tracking ms, mean "
                  "| / %s's |" % stock)
            print("|---|---|---|---|---|---|---|---|---|---|---|---|")
            base = [r["track_ms"] for r in group if r["conf"] == stock and r["track_ms"]]
            for conf in confs:
                rs = [r for r in group if r["conf"] == conf]
                if not rs:
                    continue
                times = [r["track_ms"] for r in rs if r["track_ms"]]
                ratio = "%.2f" % (statistics.median(times) / statistics.median(base)) if base and times else "–"
                print("| %s | %d | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (
                    conf, len(rs), cell([r["keyframes"] for r in rs], "%.0f"), cell([r["second"] for r in rs], "%.0f"),
                    count(rs, "reset"),
                    count(rs, "relocalised"), cell([r["obliquity"] for r in rs]), count(rs, "loop"),
                    count(rs, "correct"),
                    cell([r["ate"] for r in rs], "%.3f"), cell(times), ratio))
    groundtruth = os.path.join(runs, "kitti", "groundtruth.txt")
    if os.path.exists(groundtruth):
        print("\nKITTI 00 (frames 0–159), monocular\n")
        kitti(os.path.join(runs, "kitti"), groundtruth, confs)

    print("\nWorse than %s beyond the run-to-run range (every run of the configuration worse than every run of "
          "%s):\n" % (stock, stock))
    found = 0
    for seq in sorted({r["seq"] for r in rows}):
        for mode in ("rgbd", "mono"):
            base = [r for r in rows if r["seq"] == seq and r["mode"] == mode and r["conf"] == stock]
            for conf in confs[1:]:
                rs = [r for r in rows if r["seq"] == seq and r["mode"] == mode and r["conf"] == conf]
                for key, label, larger_better in REGRESSION_METRICS:
                    a = [r[key] for r in rs if r[key] is not None]
                    b = [r[key] for r in base if r[key] is not None]
                    if key == "ate":  # a run without a trajectory has no ATE: it is not better
                        a += [float("inf")] * sum(1 for r in rs if r[key] is None and r["keyframes"] is not None)
                    if len(a) < kMinRuns or len(b) < kMinRuns:
                        continue
                    worse = max(a) < min(b) if larger_better else min(a) > max(b)
                    if worse:
                        found += 1
                        print("- %s %s %s: %s %s against %s's %s" % (
                            seq, mode, conf, label, " ".join("%.3g" % v for v in a), stock,
                            " ".join("%.3g" % v for v in b)))
    if not found:
        print("- none")


def first_map(log):
    """(keyframes the first map made before it was lost or None, 'dropped'/'kept'/'tracked on', merged)
    from an ORB-SLAM3 log: the order of its map resets, new maps and map starts."""
    events = re.findall(r"(%s)|Creation of new map with id: (\d+)|First KF:(\d+);" % re.escape(kOrbSlam3Reset), log)
    starts = [int(k) for _, _, k in events if k]
    keyframes = starts[1] if len(starts) > 1 else None
    fate = "tracked on"
    for reset, new_map, _ in events:
        if reset:
            fate = "dropped"
            break
        if new_map and int(new_map) > 0:
            fate = "kept"
            break
    return keyframes, fate, "Merge detected" in log


def atlas(runs, confs):
    print("| sequence | mode | configuration | runs | keyframes of the first map when lost | dropped | kept "
          "| tracked on | runs with a map merge |")
    print("|---|---|---|---|---|---|---|---|---|")
    groups = {}
    for conf in confs:
        for d in sorted(glob.glob(os.path.join(runs, conf, "*", "*_*"))):
            m = re.fullmatch(r"(rgbd|mono)_\d+", os.path.basename(d))
            if not m or not os.path.exists(os.path.join(d, "log.txt")):
                continue
            groups.setdefault((os.path.basename(os.path.dirname(d)), m.group(1), conf), []).append(
                first_map(read_log(d)))

    def row(name, mode, conf, rs):
        print("| %s | %s | %s | %d | %s | %d | %d | %d | %d |" % (
            name, "RGB-D" if mode == "rgbd" else "monocular", conf, len(rs), cell([r[0] for r in rs], "%.0f"),
            sum(r[1] == "dropped" for r in rs), sum(r[1] == "kept" for r in rs),
            sum(r[1] == "tracked on" for r in rs), sum(r[2] for r in rs)))

    for kind in sorted({sequence_type(g[0]) for g in groups}):
        for mode in ("rgbd", "mono"):
            seqs = sorted({g[0] for g in groups if sequence_type(g[0]) == kind and g[1] == mode}, key=sequence_seed)
            for seq in seqs:
                for conf in confs:
                    if (seq, mode, conf) in groups:
                        row(seq, mode, conf, groups[(seq, mode, conf)])
            if len(seqs) > 1:
                for conf in confs:
                    pooled = [r for seq in seqs for r in groups.get((seq, mode, conf), [])]
                    if pooled:
                        row("%s, %d sequences" % (kind, len(seqs)), mode, conf, pooled)


def keyframe_maps(runs, conf, seq):
    """(runs, [(timestamps, poses)]): the monocular runs of CONF on SEQ and the last map of every one
    with >= 3 keyframes (keyframe_map)."""
    directories = sorted(glob.glob(os.path.join(runs, conf, seq, "mono_*")))
    maps = [keyframe_map(d) for d in directories]
    return len(directories), [m for m in maps if m is not None]


def scale_drift(t_gt, p_gt, t, p):
    """Largest over smallest Sim(3) scale of windows of kDriftWindow consecutive associated keyframes
    (windows start every kDriftWindow // 3), or None for a map of fewer keyframes."""
    ie, ig = ate.associate(t, t_gt)
    if len(ie) < kDriftWindow:
        return None
    scales = [ate.umeyama(p[ie[i:i + kDriftWindow], :3], p_gt[ig[i:i + kDriftWindow], :3], True)[0]
              for i in range(0, len(ie) - kDriftWindow + 1, kDriftWindow // 3)]
    return max(scales) / min(scales)


def map_errors(t_gt, p_gt, t, p, begin, end):
    """(Sim(3) ATE of the whole map, of its keyframes in [begin, end] (None for fewer than 3), scale drift)."""
    res, _ = ate.evaluate(t_gt, p_gt, t, p, sim3=True)
    keep = (t >= begin) & (t <= end)
    inside = ate.evaluate(t_gt, p_gt, t[keep], p[keep], sim3=True)[0] if keep.sum() >= 3 else {}
    return (res["ate"]["rmse"] if "ate" in res else None, inside["ate"]["rmse"] if "ate" in inside else None,
            scale_drift(t_gt, p_gt, t, p))


def span_row(name, span_text, conf, runs, errors):
    inside = [e[1] for e in errors if e[1] is not None]
    print("| %s | %s | %s | %d/%d | %s | %s | %s | %s |" % (
        name, span_text, conf, len(errors), runs, cell([e[0] for e in errors], "%.3f"), cell(inside, "%.3f"),
        "%d/%d" % (sum(1 for a in inside if a <= kCorrectMapM), len(inside)) if inside else "–",
        cell([e[2] for e in errors], "%.2f")))


def span(runs, seqs, confs):
    sequences = sorted({os.path.basename(os.path.dirname(d)) for c in confs
                        for d in glob.glob(os.path.join(runs, c, "*", "mono_*"))},
                       key=lambda q: (sequence_type(q), sequence_seed(q)))
    print("| sequence | span, s from the first frame | configuration | maps / runs | ATE m, whole map "
          "| ATE m, inside the span | correct inside the span (<= %.2f m) | scale drift, max/min |" % kCorrectMapM)
    print("|---|---|---|---|---|---|---|---|")
    pooled = {}
    for seq in sequences:
        truth = os.path.join(seqs, seq, "groundtruth.txt")
        if not os.path.exists(truth):
            continue
        t_gt, p_gt = ate.read_tum(truth)
        found = {c: keyframe_maps(runs, c, seq) for c in confs}
        every = [m for c in confs for m in found[c][1]]
        begin = max((t[0] for t, _ in every), default=0.0)
        end = min((t[-1] for t, _ in every), default=0.0)
        span_text = "%.1f–%.1f" % (begin - t_gt[0], end - t_gt[0]) if end > begin else "none"
        for conf in confs:
            n, maps = found[conf]
            if n == 0:
                continue
            errors = [map_errors(t_gt, p_gt, t, p, begin, end) for t, p in maps]
            group = pooled.setdefault((sequence_type(seq), conf), [0, 0, []])
            group[0] += 1
            group[1] += n
            group[2] += errors
            span_row(seq, span_text, conf, n, errors)
    for (kind, conf), (sequences_of_kind, n, errors) in sorted(pooled.items(),
                                                              key=lambda g: (g[0][0], confs.index(g[0][1]))):
        if sequences_of_kind > 1:
            span_row("%s, %d sequences" % (kind, sequences_of_kind), "", conf, n, errors)


def main(argv):
    if len(argv) >= 4 and argv[0] == "relocalisation":
        relocalisation(argv[1], argv[2], argv[3:])
    elif len(argv) >= 3 and argv[0] == "monocular":
        monocular(argv[1], argv[2:])
    elif len(argv) >= 3 and argv[0] == "rgbd":
        rgbd(argv[1], argv[2:])
    elif len(argv) >= 4 and argv[0] == "suite":
        suite(argv[1], argv[2], argv[3:])
    elif len(argv) >= 3 and argv[0] == "atlas":
        atlas(argv[1], argv[2:])
    elif len(argv) >= 4 and argv[0] == "span":
        span(argv[1], argv[2], argv[3:])
    elif len(argv) >= 4 and argv[0] == "kitti":
        kitti(argv[1], argv[2], argv[3:])
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main(sys.argv[1:])
