"""The figure of docs/prediction.md: |predicted/simulated - 1| of the task error against each tool's
initial distance to the goal, from the CSVs benches/prediction.sh writes (standard library only).

Usage: python3 benches/prediction_figure.py target/prediction docs/img/prediction_error.svg
"""
import csv
import math
import sys

SERIES = [("panda_touch", "Panda touch", "#1f77b4"), ("ur5_touch", "UR5 touch", "#ff7f0e"),
          ("arm2_position", "paper's arm, position", "#2ca02c")]
W, H, L, B = 640, 420, 70, 50


def points(folder, name):
    with open(f"{folder}/{name}.csv") as f:
        for r in csv.DictReader(f):
            d, p, s = (float(r[k]) for k in ("distance", "predicted_task_error", "simulated_task_error"))
            if d > 0 and s > 0 and p != s:
                yield d, abs(p / s - 1)


def main(folder, out):
    data = {n: list(points(folder, n)) for n, _, _ in SERIES}
    xs = [math.log10(d) for v in data.values() for d, _ in v]
    ys = [math.log10(e) for v in data.values() for _, e in v]
    x0, x1, y0, y1 = math.floor(min(xs)), math.ceil(max(xs)), math.floor(min(ys)), math.ceil(max(ys))
    sx = lambda x: L + (math.log10(x) - x0) / (x1 - x0) * (W - L - 20)
    sy = lambda y: H - B - (math.log10(y) - y0) / (y1 - y0) * (H - B - 20)
    svg = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="12">',
           f'<rect width="{W}" height="{H}" fill="white"/>',
           f'<line x1="{L}" y1="{H-B}" x2="{W-20}" y2="{H-B}" stroke="black"/>',
           f'<line x1="{L}" y1="20" x2="{L}" y2="{H-B}" stroke="black"/>']
    for k in range(x0, x1 + 1):
        x = sx(10.0 ** k)
        svg.append(f'<text x="{x:.1f}" y="{H-B+16}" text-anchor="middle">1e{k}</text>')
    for k in range(y0, y1 + 1):
        y = sy(10.0 ** k)
        svg.append(f'<text x="{L-6}" y="{y+4:.1f}" text-anchor="end">1e{k}</text>')
        svg.append(f'<line x1="{L}" y1="{y:.1f}" x2="{W-20}" y2="{y:.1f}" stroke="#ddd"/>')
    for i, (name, label, colour) in enumerate(SERIES):
        for d, e in data[name]:
            svg.append(f'<circle cx="{sx(d):.1f}" cy="{sy(e):.1f}" r="1.6" fill="{colour}" fill-opacity="0.5"/>')
        svg.append(f'<circle cx="{L+20}" cy="{30+16*i}" r="4" fill="{colour}"/>')
        svg.append(f'<text x="{L+30}" y="{34+16*i}">{label}</text>')
    svg.append(f'<text x="{(W+L)/2}" y="{H-12}" text-anchor="middle">initial distance of the error term to its goal (m or rad)</text>')
    svg.append(f'<text transform="translate(16,{(H-B)/2}) rotate(-90)" text-anchor="middle">|predicted/simulated task error - 1|</text>')
    svg.append("</svg>")
    with open(out, "w") as f:
        f.write("\n".join(svg) + "\n")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
