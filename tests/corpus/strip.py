#!/usr/bin/env python3
"""Prepare a corpus URDF: drop what the dynamics never read (meshes and appearance).

Usage: strip.py IN.urdf OUT.urdf

Removes every <visual>, <collision>, <gazebo> and <transmission> element (meshes, materials,
simulator and actuator plugins); links, joints, <inertial>, <limit>, <dynamics>, <mimic> and
<calibration> are written back unchanged (number strings as in the source; XML comments are
dropped). Used once, by hand, to make the files of tests/corpus from their sources (SOURCES.md).
"""
import sys
import xml.etree.ElementTree as ET

DROP = {"visual", "collision", "gazebo", "transmission"}


def strip(element):
    for child in list(element):
        if child.tag in DROP:
            element.remove(child)
        else:
            strip(child)


def main():
    src, dst = sys.argv[1], sys.argv[2]
    tree = ET.parse(src)
    strip(tree.getroot())
    ET.indent(tree, space="  ")
    tree.write(dst, encoding="unicode", xml_declaration=False)
    with open(dst, "a", encoding="utf-8") as f:
        f.write("\n")


if __name__ == "__main__":
    main()
