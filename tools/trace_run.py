"""Count the duplicated work behind one `xval run` (issue 27's trace).

    python tools/trace_run.py run rotor-spinup --set torque=3.2 --set t_end=1 --out DIR

Prints, for the command given: project files and functions entered, calls of `get_scene`,
`Solver.leaf` (and `LeafInfo` look-ups and builds), output-grid builds, settings checks
(`merge_settings`, leaves' `check_settings`) and warm-up calls (a leaf's `simulate` on a
two-point grid).
"""
import collections
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PROJECT = tuple(str(ROOT / d) for d in ("compare", "custom_models", "reference_models", "xval"))
COUNTED = {"get_scene": "get_scene", "leaf": "Solver.leaf", "leaf_info": "leaf_info look-ups",
           "_build": "leaf views built (LeafInfo)",
           "output_grid": "output grid built", "merge_settings": "settings checked (merge)",
           "check_settings": "settings checked (check_settings)"}


def main(argv):
    calls, files, warm = collections.Counter(), collections.defaultdict(set), [0]

    def prof(frame, event, arg):
        if event != "call":
            return
        code = frame.f_code
        if not code.co_filename.startswith(PROJECT):
            return
        files[code.co_filename].add(code.co_name)
        if code.co_name in COUNTED:
            calls[COUNTED[code.co_name]] += 1
        if code.co_name == "simulate" and code.co_filename.startswith(PROJECT[1:3]):
            t = frame.f_locals.get("t_out")
            if t is not None and len(t) == 2:
                warm[0] += 1

    from compare import cli
    sys.setprofile(prof)
    try:
        rc = cli.main(argv)
    except SystemExit as e:
        rc = e.code
    finally:
        sys.setprofile(None)
    imported_only = sum(names == {"<module>"} for names in files.values())
    print(f"exit {rc}; project files entered: {len(files)} ({imported_only} only imported: "
          f"package markers, constants, numba kernels whose calls the profiler cannot see); "
          f"functions entered: {sum(map(len, files.values()))}", file=sys.stderr)
    for name in COUNTED.values():
        print(f"  {name}: {calls[name]}", file=sys.stderr)
    print(f"  warm-up calls (simulate on a 2-point grid): {warm[0]}", file=sys.stderr)


if __name__ == "__main__":
    main(sys.argv[1:])
