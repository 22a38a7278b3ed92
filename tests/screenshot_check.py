#!/usr/bin/python3
"""Checks a screenshot of a report page: the 3D view (the top of the page, below its title bar)
is not blank. Prints the count of distinct colours there; exits 1 below `min_colours`.

Usage: screenshot_check.py PNG [min_colours]
"""
import sys

import matplotlib.image


def main():
    image = matplotlib.image.imread(sys.argv[1])
    minimum = int(sys.argv[2]) if len(sys.argv) > 2 else 50
    h = image.shape[0]
    view = image[int(0.06 * h):int(0.6 * h), :, :3]
    colours = {tuple(p) for p in (view * 255).round().astype(int).reshape(-1, 3)}
    print(f"{len(colours)} distinct colours in the 3D view")
    return 0 if len(colours) >= minimum else 1


if __name__ == "__main__":
    sys.exit(main())
