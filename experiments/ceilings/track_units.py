import sys
from pathlib import Path
from experiments.tracking import run_unit
name = sys.argv[1]
for u in sys.argv[2].split(","):
    seq, seed = u.split(":")
    r = run_unit(Path(sys.argv[3]), name, seq, int(seed))
    print(seq, seed, name, round(r["mpjpe_mm"]), flush=True)
