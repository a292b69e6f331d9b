"""Parameter sweeps: one scene run once per sample, with named scene values varied.

``massprops sweep SCENE --vary KEY=SPEC ... --samples N --seed S`` (the contract's "sweep").
Modules, in the order a sweep uses them:

- `keys`: paths to scene values (``bodies.upper.mass``, ``forces[0].stiffness``) and to a run's
  outputs (``final.joints.elbow.force``);
- `specs`: how a value varies (normal, uniform, lognormal, relative, a grid of values);
- `inertials`: a body's mass, inertia and centre of mass varied as a body's can be, and a
  mesh body's within inspect's error bars (``--bars``), every draw a valid inertial;
- `sample`: one sample (its values from the seed and its index alone, its scene, its run);
- `run`: the plan checked and run once, then every sample, here or on a pool or a Dask
  cluster, rows in sample order;
- `summary`: each output's spread, its uncertainty and its sensitivity to each value;
- `linear`: derivatives from the engine itself (``--linear``); `plots`: bands over time;
- `session`: `Sweep`, all of it as one object (plan, pool or cluster, rows, summary);
- `table`: the rows as CSV.

The library prints nothing; ``cli/sweep.py`` opens a `Sweep`, prints its rows, renders.
"""

from massprops.sweep.run import Prepared, default_outputs, prepare, run_sweep
from massprops.sweep.sample import Row
from massprops.sweep.session import Sweep
from massprops.sweep.summary import summarize

__all__ = ["Prepared", "Row", "Sweep", "default_outputs", "prepare", "run_sweep", "summarize"]
