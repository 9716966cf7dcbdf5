#!/usr/bin/env python3
"""Derives data/imucal-ferraris/ferraris_raw_means.csv from imucal's labelled Ferraris session.

Input: imucal's example_data/annotated_session.csv (columns part, samples, acc_x..z, gyr_x..z; raw
counts; each static hold labelled x_p, x_a, y_p, y_a, z_p, z_a). Output: one averaged reading per
hold, in that order, with the sample count and the per-axis sample standard deviation
(accelcal's positions-file layout x,y,z,n,sx,sy,sz). Standard library only.

Usage: python3 scripts/derive-ferraris-means.py annotated_session.csv > ferraris_raw_means.csv
"""
import csv
import statistics
import sys

HOLDS = ["x_p", "x_a", "y_p", "y_a", "z_p", "z_a"]


def main(path):
    samples = {}
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            samples.setdefault(row["part"], []).append(
                [float(row["acc_x"]), float(row["acc_y"]), float(row["acc_z"])])
    print("x,y,z,n,sx,sy,sz")
    for hold in HOLDS:
        values = samples[hold]
        axes = list(zip(*values))
        means = [statistics.fmean(a) for a in axes]
        stds = [statistics.stdev(a) for a in axes]
        print(",".join(repr(v) for v in means) + f",{len(values)}," +
              ",".join(repr(v) for v in stds))


if __name__ == "__main__":
    main(sys.argv[1])
