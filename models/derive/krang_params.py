#!/usr/bin/env python3
"""Derive the default [parameters] of models/krang.toml and krang-fixed-wheels.toml from Krang.urdf.

Usage (pure Python >= 3.11, no third-party packages):

    python3 models/derive/krang_params.py [--urdf PATH] [--model PATH] [--reference PATH] [--no-wheels]

Prints the [parameters] block (one `# body N (URDF link NAME)` group per body) on stdout and a
report on stderr:
  * every URDF joint used is checked against the model's frames: its rpy must be the model's
    iAj(0) (to the URDF's rounding of pi: 3.1416, "3.14"), its axis the model's e_j, and its
    origin the model's iPj apart from the lateral offsets the reports drop (listed);
  * LJFT/RJFT must equal 9A10(0)·Rot(e10, pi/2) (so the gripper link frame is report frame 10 at
    q7(report) = q7(URDF) + pi/2 and its inertia needs no rotation);
  * the derived values are compared with case 1 of reference-values.json (max abs/rel difference).

Conversion (Khalil's standard form, in the body's own frame): with the inertial origin's xyz = S
and rpy = R_in (identity if absent; no link of Krang.urdf has one) and the URDF inertia I_c about
the centre of mass in the inertial frame,
    I_G = R_in I_c R_inᵀ,   MS = [MX, MY, MZ] = m S,   J = I_G + m (|S|² 1 − S Sᵀ),
    XX = J[0][0], XY = J[0][1], XZ = J[0][2], YY = J[1][1], YZ = J[1][2], ZZ = J[2][2].

Left out (see the header of models/krang.toml): the gripper plates lgPlate1/2, rgPlate1/2 (fixed
children, 0.1 g, placeholder inertias ~0.09 kg m^2) and the Kinect (commented out in Krang.urdf).
The default paths are the repository's copies (models/Krang.urdf, models/krang/reference-values.json).
"""

import argparse
import json
import math
import sys
import tomllib
import xml.etree.ElementTree as ET
from pathlib import Path

HERE = Path(__file__).resolve().parent
DEFAULT_URDF = HERE.parent / "Krang.urdf"
DEFAULT_REFERENCE = HERE.parent / "krang" / "reference-values.json"
DEFAULT_MODEL = HERE.parent / "krang.toml"

# Report body <- URDF link.
BODIES = [("1", "Base"), ("2", "Spine"), ("3", "Bracket")]
for side, prefix, grip in (("l", "L", "lGripper"), ("r", "R", "rGripper")):
    BODIES += [(f"{k + 4}{side}", f"{prefix}{k + 1}") for k in range(6)]
    BODIES.append((f"10{side}", grip))

# Model joint (child frame) <- URDF joint.
JOINTS = {"2": "JWaist", "3": "JTorso"}
for side, prefix in (("l", "L"), ("r", "R")):
    JOINTS.update({f"{k + 4}{side}": f"{prefix}J{k + 1}" for k in range(6)})
    JOINTS[f"10{side}"] = f"{prefix}JFT"

# Links of the URDF that are not report bodies, and why they are left out.
DROPPED = {
    "LWheel": "wheel: enters through mw, YYw, ZZw (see the wheel constants)",
    "RWheel": "wheel: enters through mw, YYw, ZZw (see the wheel constants)",
    "lgPlate1": "fixed child of lGripper, 0.1 g, placeholder inertia (~0.09 kg m^2): dropped",
    "lgPlate2": "fixed child of lGripper, 0.1 g, placeholder inertia (~0.09 kg m^2): dropped",
    "rgPlate1": "fixed child of rGripper, 0.1 g, placeholder inertia (~0.09 kg m^2): dropped",
    "rgPlate2": "fixed child of rGripper, 0.1 g, placeholder inertia (~0.09 kg m^2): dropped",
}

# Lengths: (symbol, URDF joint, index into its origin xyz, sign) so that symbol = sign * xyz[index].
LENGTHS = [
    ("L1", "JWaist", 1, 1), ("L2", "JWaist", 2, -1),
    ("L3", "JTorso", 1, 1), ("L4", "JTorso", 2, 1),
    ("L5", "LJ1", 1, 1), ("L6", "LJ1", 0, 1),
    ("L7", "LJ3", 1, -1), ("L8", "LJ5", 1, -1), ("L9", "LJFT", 1, -1),
]

# Wheel and gravity constants (see the header of models/krang.toml).
G = 9.81
WHEEL_R = 0.25  # controllers' wheel radius
WHEEL_L = 0.68  # controllers' track width
YYW = 0.1456  # solid disc about the axle: mw R²/2 = 0.145625, to 4 digits as in the reference
ZZW = 0.0751  # about a diameter: mw R²/4 + mw w²/12 = 0.0751 for a width w ≈ 0.077 m (reference)

ANGLE_TOL = 2e-3  # the URDF writes pi as 3.1416 and, on LJ2/RJ2, as 3.14


def matmul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def transpose(a):
    return [[a[j][i] for j in range(3)] for i in range(3)]


def rpy_matrix(r, p, y):
    """URDF convention: R = Rz(y) Ry(p) Rx(r)."""
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    rx = [[1, 0, 0], [0, cr, -sr], [0, sr, cr]]
    ry = [[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]]
    rz = [[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]]
    return matmul(rz, matmul(ry, rx))


def axis_rotation(e, q):
    """Rodrigues: rotation by q about the unit vector e."""
    c, s, v = math.cos(q), math.sin(q), 1 - math.cos(q)
    x, y, z = e
    return [
        [c + x * x * v, x * y * v - z * s, x * z * v + y * s],
        [y * x * v + z * s, c + y * y * v, y * z * v - x * s],
        [z * x * v - y * s, z * y * v + x * s, c + z * z * v],
    ]


def max_diff(a, b):
    return max(abs(a[i][j] - b[i][j]) for i in range(3) for j in range(3))


def floats(text, n=3):
    v = [float(t) for t in (text or " ".join(["0"] * n)).split()]
    assert len(v) == n, text
    return v


def body_parameters(link):
    """m, MS, J (Khalil form) of a URDF <link>."""
    inertial = link.find("inertial")
    m = float(inertial.find("mass").get("value"))
    origin = inertial.find("origin")
    s = floats(origin.get("xyz") if origin is not None else None)
    rin = rpy_matrix(*floats(origin.get("rpy") if origin is not None else None))
    i = inertial.find("inertia").attrib
    ic = [
        [float(i["ixx"]), float(i["ixy"]), float(i["ixz"])],
        [float(i["ixy"]), float(i["iyy"]), float(i["iyz"])],
        [float(i["ixz"]), float(i["iyz"]), float(i["izz"])],
    ]
    ig = matmul(rin, matmul(ic, transpose(rin))) if rin != [[1, 0, 0], [0, 1, 0], [0, 0, 1]] else ic
    # m|S|² 1 − m S Sᵀ, evaluated in this order: it reproduces reference-values.json bit for bit
    # (other orders of the same sums differ from it by 1 ulp here and there).
    s2 = s[0] ** 2 + s[1] ** 2 + s[2] ** 2
    shift = [[(m * s2 if a == b else 0.0) - m * (s[a] * s[b]) for b in range(3)] for a in range(3)]
    j = [[ig[a][b] + shift[a][b] for b in range(3)] for a in range(3)]
    ms = [m * s[0], m * s[1], m * s[2]]
    return m, ms, [j[0][0], j[0][1], j[0][2], j[1][1], j[1][2], j[2][2]]


def check_frames(urdf_joints, model, note):
    """Compare each URDF joint with the model's joint of the same child frame."""
    by_child = {j["child"]: j for j in model["joint"]}
    params = model["parameters"]
    for child, uname in JOINTS.items():
        uj = urdf_joints[uname]
        mj = by_child[child]
        o = uj.find("origin")
        r_urdf = rpy_matrix(*floats(o.get("rpy")))
        a_model = mj["rotation"]
        e = mj["axis"]
        if child.startswith("10"):
            a_model = matmul(a_model, axis_rotation(e, math.pi / 2))
        d = max_diff(r_urdf, a_model)
        assert d < ANGLE_TOL, (uname, d)
        u_axis = floats(uj.find("axis").get("xyz"))
        assert u_axis == [float(x) for x in e], (uname, u_axis, e)
        xyz = floats(o.get("xyz"))
        p = [t if isinstance(t, (int, float)) else
             (-params[t[1:]] if t.startswith("-") else params[t]) for t in mj["translation"]]
        for k in range(3):
            if abs(xyz[k] - p[k]) > 1e-12:
                note(f"{uname}: origin {'xyz'[k]} = {xyz[k]} in the URDF, {p[k]} in the model (dropped)")
        note(f"{uname} -> frame {child}: |R_urdf - A_model{'·Rot(e10, pi/2)' if child.startswith('10') else ''}| = {d:.1e}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--urdf", type=Path, default=DEFAULT_URDF)
    ap.add_argument("--model", type=Path, default=DEFAULT_MODEL, help="TOML model whose frames are checked")
    ap.add_argument("--reference", type=Path, default=DEFAULT_REFERENCE)
    ap.add_argument("--no-wheels", action="store_true", help="omit R, L, mw, YYw, ZZw")
    args = ap.parse_args()

    def note(msg):
        print(msg, file=sys.stderr)

    robot = ET.parse(args.urdf).getroot()  # comments (the Kinect) are not elements
    links = {l.get("name"): l for l in robot.findall("link")}
    joints = {j.get("name"): j for j in robot.findall("joint")}
    used = {u for _, u in BODIES}
    for name in links:
        if name not in used:
            assert name in DROPPED, f"URDF link {name} is neither a body nor known to be dropped"
            note(f"not a body: {name}: {DROPPED[name]}")
    for name, j in joints.items():
        if j.get("type") == "fixed":
            note(f"fixed joint {name}: {j.find('parent').get('link')} -> {j.find('child').get('link')}")

    with open(args.model, "rb") as f:
        check_frames(joints, tomllib.load(f), note)

    values = {}
    for sym, jname, k, sign in LENGTHS:
        values[sym] = sign * floats(joints[jname].find("origin").get("xyz"))[k]
    assert floats(joints["RJ1"].find("origin").get("xyz"))[0] == -values["L6"]
    values["g"] = G
    if not args.no_wheels:
        lw, rw = links["LWheel"], links["RWheel"]
        mw = float(lw.find("inertial/mass").get("value"))
        assert mw == float(rw.find("inertial/mass").get("value"))
        values.update(R=WHEEL_R, L=WHEEL_L, mw=mw, YYw=YYW, ZZw=ZZW)
        note(f"solid disc: mw R^2/2 = {mw * WHEEL_R**2 / 2}, mw R^2/4 = {mw * WHEEL_R**2 / 4}; "
             f"width for ZZw: {math.sqrt((ZZW - mw * WHEEL_R**2 / 4) * 12 / mw):.4f} m")

    comments = {
        sym: f"-({jname} origin {'xyz'[k]})" if sign < 0 else f"{jname} origin {'xyz'[k]}"
        for sym, jname, k, sign in LENGTHS
    }
    comments.update(R="controllers' wheel radius", L="controllers' track width", mw="URDF LWheel/RWheel mass",
                    YYw="solid disc, about the axle", ZZw="solid disc, about a diameter")
    out = ["[parameters]"]
    for k, v in values.items():
        out.append(f"{k} = {v!r}" + (f"  # {comments[k]}" if k in comments else ""))
    for body, lname in BODIES:
        m, ms, j = body_parameters(links[lname])
        out.append(f"# body {body} (URDF link {lname})")
        names = ["m", "MX", "MY", "MZ", "XX", "XY", "XZ", "YY", "YZ", "ZZ"]
        for n, v in zip(names, [m, *ms, *j]):
            values[n + body] = v
            out.append(f"{n}{body} = {v!r}")
    print("\n".join(out))

    if args.reference.exists():
        ref = json.loads(args.reference.read_text())["cases"][0]["params"]
        missing = sorted(set(ref) ^ set(values))
        worst = max(((abs(values[k] - ref[k]), k) for k in values if k in ref))
        worst_rel = max(((abs(values[k] - ref[k]) / max(abs(ref[k]), 1e-300), k) for k in values if k in ref))
        note(f"vs reference case 1: max |diff| = {worst[0]:.3e} ({worst[1]}), "
             f"max rel = {worst_rel[0]:.3e} ({worst_rel[1]}); symbols not in both: {missing}")


if __name__ == "__main__":
    main()
