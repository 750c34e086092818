"""How problems/recordings/box_transfer.c3d was made from pyomeca's sample recording.

The source: github.com/pyomeca/pyomeca, tests/data/markers_analogs.c3d (Apache License 2.0,
Copyright Romain Martinez & Benjamin Michaud, 2020; LICENSE.pyomeca here). Changed: the 38
analog channels (EMG and voltages, 2000 Hz) dropped; the subject's name removed from the
marker labels ("<name>:STER" becomes "STER"; the box's markers keep "boite:"); every second
frame kept (100 Hz to 50 Hz). The marker coordinates are copied unchanged (mm).

    python problems/recordings/derive_box_transfer.py markers_analogs.c3d box_transfer.c3d
"""

import argparse

import ezc3d


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("source", help="pyomeca's tests/data/markers_analogs.c3d")
    parser.add_argument("target", help="the markers-only file to write")
    args = parser.parse_args()
    source = ezc3d.c3d(args.source)
    point = source["parameters"]["POINT"]
    labels = [label.split(":", 1)[1] if ":" in label and not label.startswith("boite:")
              else label for label in point["LABELS"]["value"]]  # fmt: skip
    target = ezc3d.c3d()
    target["parameters"]["POINT"]["RATE"]["value"] = [float(point["RATE"]["value"][0]) / 2]
    target["parameters"]["POINT"]["LABELS"]["value"] = labels
    target["parameters"]["POINT"]["UNITS"]["value"] = ["mm"]
    target["data"]["points"] = source["data"]["points"][:, :, ::2].copy()
    target.write(args.target)


if __name__ == "__main__":
    main()
