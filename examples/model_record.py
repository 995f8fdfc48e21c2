"""Write the oblique scene's vehicle accelerations as a crash-test record, and assess it.

    python examples/model_record.py [OUT.csv]

`examples/oblique_scene.toml` is MASH test 3-11's vehicle, speed and angle (a 2270 kg pickup
at 100 km/h and 25 degrees) on the report's barrier. `barrierjax.assess.vehicle_record`
gives what an accelerometer at the vehicle's centre of gravity would record in the model
(10 kHz, on the vehicle's axes); this script writes it the way test houses export records
(`t [ms]`, `ax [g]`, `ay [g]`) to `examples/oblique_scene_record.csv` (or OUT.csv), and
prints the occupant risk against MASH's limits. `barrierjax assess
examples/oblique_scene_record.csv` reads it back (add `--cfc 0` for the same numbers: by
default the command first filters at CFC 180, as for a measured record).
"""

import sys
from pathlib import Path

import jax
import numpy as np

jax.config.update("jax_enable_x64", True)

import barrierjax as bj
from barrierjax import assess

G = 9.80665
here = Path(__file__).resolve().parent
out = Path(sys.argv[1]) if len(sys.argv) > 1 else here / "oblique_scene_record.csv"

result = bj.simulate(bj.load_scene(here / "oblique_scene.toml"))
t, ax, ay = assess.vehicle_record(result.history)
rows = np.column_stack([t * 1e3, np.asarray(ax) / G, np.asarray(ay) / G])
np.savetxt(out, rows, fmt="%.9g", delimiter=",", header="t [ms],ax [g],ay [g]", comments="")
print(f"wrote {out} ({len(t)} samples, {t[-1] * 1e3:.1f} ms)")

risk = assess.occupant_risk(t, ax, ay)
for criterion in assess.judge(risk, "mash"):
    print(f"{criterion.name:6s} {criterion.value:8.2f} {criterion.unit:6s} {criterion.verdict}")
