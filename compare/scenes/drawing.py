"""What the scenes' 3-D views share: a mechanism drawn as line strips at the solver's output
times (`Scene.draw_3d` hooks call it; rerun is imported only when a recording is made)."""
import numpy as np


def send_strips(rec, entity, times, strips, colors, radius, per=1):
    """`strips` (per output time in `times`, `per` strips each, in order) as one LineStrips3D
    column on the `sim_time` timeline; `colors`: one per strip."""
    import rerun as rr
    columns = rr.LineStrips3D.columns(strips=strips, colors=colors, radii=[radius] * len(strips))
    if per != 1:
        columns = columns.partition([per] * len(times))
    rec.send_columns(entity, indexes=[rr.TimeColumn("sim_time", duration=np.asarray(times))],
                     columns=columns)
