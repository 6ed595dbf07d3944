"""A copy of the eval tests' dataset whose sphere tour has one motion no two touches on the sphere
can make (the fourth touch's hop 5 m): `vtloc eval --sequence` must refuse it by file and touch.
   python3 make_far_hop.py SRC DST"""
import csv
import shutil
import sys

src, dst = sys.argv[1], sys.argv[2]
shutil.rmtree(dst, ignore_errors=True)
shutil.copytree(src, dst)
path = dst + "/objects/sphere/touches.csv"
with open(path, newline="") as f:
    rows = list(csv.DictReader(f))
hit = [r for r in rows if r["order"] == "3"]
assert len(hit) == 1, "no touch of order 3"
hit[0]["qx"] = "5000"
with open(path, "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
    w.writeheader()
    w.writerows(rows)
print("id", hit[0]["id"])
