"""The units of the readings of real dual-unit and dual-scale dials, against units read by eye.

    python bench/investigations/units_real.py [--shared ../shared/datasets]

Reads every photo of needle-polygons `valid` and `train` (one of each photo's augmented copies) and
of gauge-readings-dev, and for each reading on a dial in :data:`MAIN_UNIT` prints the unit the reader
gave it, the scales it fitted with their units, and the units it read on the dial. :data:`MAIN_UNIT`
holds, by eye (session 22), the unit of the scale each reading is on, for the dials that print two
units or carry two scales: the readings where "which unit" is a real question. Neither dataset labels
units, so this table is the only truth; it is small and was made by one person looking at the
reader's debug pictures (``gauged read IMAGE --debug-dir DIR``).
"""

from __future__ import annotations

import argparse
import sys
from collections import Counter
from pathlib import Path

import cv2

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # bench/, for common
from common import header  # noqa: E402

# start of a photo's name -> the unit of the scale the reader reads (the outer one unless noted), by eye
MAIN_UNIT = {
    "104-440-155-hp-gauge_1": "psi",          # 0..5000 psi outside, 0..350 bar inside
    "105-150_PSI_Water_Gauge_Adaptor": "kPa",  # 0..1000 kPa outside, 0..150 psi inside
    "12-GE3814-web": "bar",                   # 0..6 bar, 0..90 psi
    "13-AFC-600-25": "psi",                   # 0..600 psi, 0..40 bar
    "136-DSC1789_063b813a-872b-49e7-b2d1-8e0a": "bar",  # 0..250 bar, psi inside
    "191-hayward-ecx270861-bottom-mount-press": "psi",  # 0..60 psi, 0..4 bar
    "2-a1fde6ff-3004-40d2-8033-672efbbf30c6-2": "psi",  # 0..15 psi outside, 0..100 kPa inside
    "244-Hydraulic-Pressure-Gauge": "MPa",    # 0..100 MPa, psi inside
    "252-Pressure-Gauge-Calibration": "psi",  # 0..3000 psi, 0..200 bar
    "287-5530011__98538-1587192216": "bar",   # 0..16 bar, 0..230 psi
    "29-hydrant-pressure-gauge-dry-small-63mm": "kPa",  # 0..2500 kPa, 0..350 psi
    "440-1SPE_2016": "psi",                   # 0..160 psi outside, 0..11 bar inside
    "469-5730_web": "psi",                    # 0..100 psi outside, 0..7 bar inside
    "551-wika-pressure-gauges-500x500": "psi",  # 0..160 psi outside, 0..1100 kPa inside
    "241-High-Pressure-Gauge-Dual-Scale-SDL85": "psi",  # psi outside, kg/cm2 inside
    "355-6973_2_lg": "kPa",                   # the reader reads the inner 0..350 kPa ring; psi outside
    "489-PIC_PR_130_15_2917-jpg": "psi",      # 0..100 psi outside, 0..7 bar inside
    "68-GB01-High-Pressure-Gauge-Replacement": "psi",  # psi outside, 0..400 bar inside
    "71GKzopCtEL": "psi",                     # 0..300 psi outside, 0..20 bar inside
    "84b98fc3f1a34473a5800984110eabe1_jpeg": "degF",  # degF outside, degC inside
}


def main_unit(stem: str) -> str | None:
    return next((unit for start, unit in MAIN_UNIT.items() if stem.startswith(start)), None)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--shared", type=Path, default=Path(__file__).resolve().parents[2] / ".." / "shared" / "datasets")
    args = parser.parse_args()
    folders = [args.shared / "needle-polygons" / "valid" / "images", args.shared / "needle-polygons" / "train" / "images",
               args.shared / "gauge-readings-dev" / "images"]
    if not all(f.is_dir() for f in folders):
        print(f"needs {', '.join(map(str, folders))}", file=sys.stderr)
        return 2
    from gauged.config.model import ReaderConfig
    from gauged.reader.factory import build_reader
    from gauged.training.real_data import photo_group

    header("units of real dual-unit / dual-scale readings against units read by eye")
    reader = build_reader(ReaderConfig())
    counts: Counter[str] = Counter()
    seen = set()
    for path in sorted(p for f in folders for p in f.iterdir()):
        stem = photo_group(path)  # augmented copies share it
        truth = main_unit(stem)
        if stem in seen or truth is None:
            continue
        seen.add(stem)
        reads = reader.read_image(cv2.imread(str(path)))
        for read in reads if isinstance(reads, list) else []:
            if read.value is None:
                continue
            verdict = "right" if read.unit == truth else "none" if read.unit is None else "wrong"
            counts[verdict] += 1
            scales = ", ".join(f"{s.min_value:.4g}..{s.max_value:.4g} {s.unit}" for s in read.scales)
            printed = ", ".join(f"{u.unit}@{u.radius:.2f}" for u in read.units if u.radius is not None)
            print(f"{verdict:5} {stem[:40]:40} unit {read.unit!s:6} (by eye {truth:4}) "
                  f"scales [{scales}] printed [{printed}]")
    print(f"readings: {sum(counts.values())}, unit right {counts['right']}, wrong {counts['wrong']}, none {counts['none']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
