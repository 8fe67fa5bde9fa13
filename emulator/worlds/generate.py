#!/usr/bin/env python3
"""Writes the shipped worlds (emulator/worlds/*.json). Lengths in metres, angles in degrees.
Run from anywhere: python3 emulator/worlds/generate.py"""
import json, math, os

HERE = os.path.dirname(os.path.abspath(__file__))
W = 0.008  # tape width


def p(x, y):
    return {"x": round(x, 5), "y": round(y, 5)}


def pose(x, y, h):
    return {"x": round(x, 5), "y": round(y, 5), "headingDeg": round(h, 3)}


def arc(cx, cy, r, start=0.0, sweep=360.0, colour="black"):
    return {"type": "arc", "center": p(cx, cy), "radiusM": r, "startDeg": start, "sweepDeg": sweep, "widthM": W, "colour": colour}


def line(points, colour="black", closed=False):
    return {"type": "polyline", "points": [p(*q) for q in points], "widthM": W, "colour": colour, "closed": closed}


def on_circle(cx, cy, r, deg):
    a = math.radians(deg)
    return pose(cx + r * math.cos(a), cy + r * math.sin(a), deg + 90)


def world(name, desc, w, h, tapes, starts, boxes=()):
    return {"name": name, "description": desc, "widthM": w, "heightM": h, "ambientAdc": 300,
            "tapes": tapes, "boxes": list(boxes), "starts": starts}


worlds = []
worlds.append(world("straight", "A 1 m straight black line; robots start at its left end facing along it.",
                    1.2, 0.3, [line([(0.1, 0.15), (1.1, 0.15)])], [pose(0.12, 0.15, 0), pose(0.2, 0.15, 0)]))

R = 0.3
worlds.append(world("round", "Thesis A.3: a round track (circle of 0.3 m radius); three robots start 120 degrees apart, counter-clockwise.",
                    0.8, 0.8, [arc(0.4, 0.4, R)], [on_circle(0.4, 0.4, R, a) for a in (-90, 30, 150)]))

worlds.append(world("colours", "The round track with a red segment (slow down) from 0 to 60 degrees and a blue one (speed up) from 180 to 240 degrees.",
                    0.8, 0.8, [arc(0.4, 0.4, R), arc(0.4, 0.4, R, 0, 60, "red"), arc(0.4, 0.4, R, 180, 60, "blue")],
                    [on_circle(0.4, 0.4, R, a) for a in (-90, 90)]))

# Lemniscate of Bernoulli: the two lobes cross at right angles in the middle.
a, cx, cy = 0.36, 0.45, 0.3
pts = []
N = 360
for i in range(N):
    t = 2 * math.pi * i / N
    d = 1 + math.sin(t) ** 2
    pts.append((cx + a * math.cos(t) / d, cy + a * math.sin(t) * math.cos(t) / d))
x0, y0 = pts[0]
worlds.append(world("figure-eight", "A figure-eight (lemniscate, 0.72 m across) whose lobes cross at right angles in the middle.",
                    0.9, 0.6, [line(pts, closed=True)], [pose(x0, y0, 90)]))

# Fork: a straight stem that splits into a straight branch and a branch curving left.
stem_end = (0.4, 0.3)
rb = 0.25
branch = [(stem_end[0] + rb * math.sin(math.radians(k)), stem_end[1] + rb * (1 - math.cos(math.radians(k)))) for k in range(0, 46, 3)]
bx, by = branch[-1]
branch.append((bx + 0.3 * math.cos(math.radians(45)), by + 0.3 * math.sin(math.radians(45))))
worlds.append(world("fork", "A straight stem from x=0.1 m splits at x=0.4 m into a straight branch and a branch curving left to 45 degrees.",
                    1.1, 0.7, [line([(0.1, 0.3), stem_end, (1.0, 0.3)]), line(branch)], [pose(0.12, 0.3, 0)]))

# Thesis A.2: a heavy box on the line that one robot cannot push and two can.
worlds.append(world("box", "Thesis A.2: a line with a heavy box (100 g, friction 0.25: 0.245 N to slide) across it at x=0.5 m. "
                    "One robot (0.16 N stall force) cannot move it; two side by side can. Two robots start on the line, one behind the other.",
                    1.0, 0.4, [line([(0.05, 0.2), (0.95, 0.2)])], [pose(0.25, 0.2, 0), pose(0.12, 0.2, 0)],
                    [{"center": p(0.5, 0.2), "widthM": 0.04, "heightM": 0.09, "angleDeg": 0.0, "massKg": 0.1, "friction": 0.25, "movable": True}]))

# Thesis A.2 as a scenario (make push): a loop whose bottom right corner is blocked by the heavy box of "box".
# Two robots pushing straight on along the bottom edge move it out of the corner, off the loop.
L, X1, Y0, Y1, RC = 0.2, 0.65, 0.15, 0.45, 0.08
loop = [line([(L, Y0), (X1, Y0)]), arc(X1, Y0 + RC, RC, -90, 90), line([(X1 + RC, Y0 + RC), (X1 + RC, Y1 - RC)]),
        arc(X1, Y1 - RC, RC, 0, 90), line([(X1, Y1), (L, Y1)]), arc(L, Y1 - RC, RC, 90, 90),
        line([(L - RC, Y1 - RC), (L - RC, Y0 + RC)]), arc(L, Y0 + RC, RC, 180, 90)]
worlds.append(world("push", "Thesis A.2, cooperative object manipulation: a loop (0.61 x 0.30 m, corners of 80 mm radius) driven "
                    "counter-clockwise, its bottom right corner blocked by a heavy box (100 g, friction 0.25) that one robot "
                    "cannot push and two can, 140 mm wide so that two robots side by side fit its face. Two robots start on the bottom "
                    "edge, one behind the other.",
                    1.0, 0.6, loop, [pose(0.40, Y0, 0), pose(0.25, Y0, 0)],
                    [{"center": p(X1 + 0.012, Y0), "widthM": 0.04, "heightM": 0.14, "angleDeg": 0.0, "massKg": 0.1, "friction": 0.25, "movable": True}]))

# Thesis A.3 as a scenario (make track): the round track with an immovable box on it at the top.
worlds.append(world("track", "Thesis A.3, multiple robots on a track: the round track (0.3 m radius) with a fixed 40 mm box on it "
                    "at 90 degrees; three robots start 120 degrees apart, counter-clockwise.",
                    0.8, 0.8, [arc(0.4, 0.4, R)], [on_circle(0.4, 0.4, R, a) for a in (-90, 30, 150)],
                    [{"center": p(0.4, 0.4 + R), "widthM": 0.04, "heightM": 0.04, "angleDeg": 0.0, "massKg": 1.0, "friction": 0.25, "movable": False}]))

# An open floor for programs that drive freely (movements, odometry): no tape, a 4 x 4 grid of start poses.
PITCH = 0.45
worlds.append(world("open", "An open floor without tape (2 x 2 m) for programs that drive freely: 16 start poses 0.45 m apart "
                    "in a 4 x 4 grid, all facing +x, row by row from the bottom left; a square of up to 0.3 m driven "
                    "to the left from any of them stays clear of the others.",
                    2.0, 2.0, [], [pose(0.3 + PITCH * (i % 4), 0.3 + PITCH * (i // 4), 0) for i in range(16)]))

for wd in worlds:
    with open(os.path.join(HERE, wd["name"] + ".json"), "w") as f:
        json.dump(wd, f, indent=2)
        f.write("\n")
print("wrote", ", ".join(w["name"] for w in worlds))
