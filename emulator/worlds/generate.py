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

for wd in worlds:
    with open(os.path.join(HERE, wd["name"] + ".json"), "w") as f:
        json.dump(wd, f, indent=2)
        f.write("\n")
print("wrote", ", ".join(w["name"] for w in worlds))
