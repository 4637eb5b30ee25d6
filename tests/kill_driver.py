"""``substruct`` with a pause at one point of a run, for the kill tests.

Usage: ``python tests/kill_driver.py POINT substruct-arguments...``.  At ``POINT`` the process
prints ``PAUSED <POINT> <pid>`` on stderr (the pid of the process that pauses) and then waits:

- ``compute``: in the analysis, a long dense LAPACK call (``scipy.linalg.eig`` of order 1500,
  about 40 s on one core, during which Python runs no signal handler of that process);
- ``compute-short``: in the analysis, 3 s of sleep (for the concurrency test);
- ``write``: in the middle of writing the result file, after ``/model``;
- ``pictures``: after the pictures are drawn into the staging folder;
- ``commit``: after the first file of the set has moved into place (3 s: SIGINT and SIGTERM
  are held there);
- ``exit``: after the command returned, in an exit handler of the interpreter;
- ``study-write``: after the study file is written into its staging folder.

The command runs as the ``substruct`` program does (``main()`` reading ``sys.argv``).
"""

import os
import sys
import time

POINT = sys.argv[1]


def pause() -> None:
    sys.stderr.write(f"PAUSED {POINT} {os.getpid()}\n")
    sys.stderr.flush()
    if POINT == "compute":
        import numpy as np
        import scipy.linalg

        a = np.random.default_rng(0).standard_normal((1500, 1500))
        for _ in range(3):
            scipy.linalg.eig(a, a.T)
    else:
        time.sleep(3 if POINT in ("compute-short", "commit") else 120)


if POINT.startswith("compute"):
    import substruct.run.runner as runner

    real_run = runner.run_case

    def run_case(*args, **kwargs):
        pause()
        return real_run(*args, **kwargs)
    runner.run_case = run_case
elif POINT == "write":
    from substruct.io import hdf5

    real_write = hdf5._write_model

    def write_model(group, model):
        real_write(group, model)
        pause()
    hdf5._write_model = write_model
elif POINT == "pictures":
    from substruct.cli import run_command

    real_pictures = run_command.write_pictures

    def write_pictures(result, out, name):
        files = real_pictures(result, out, name)
        pause()
        return files
    run_command.write_pictures = write_pictures
elif POINT == "commit":
    real_replace = os.replace
    moved = []

    def replace(src, dst, *args, **kwargs):
        real_replace(src, dst, *args, **kwargs)
        if ".commit" in str(src):
            moved.append(dst)
            if len(moved) == 1:
                pause()
    os.replace = replace

elif POINT == "study-write":
    from substruct.io import study_file

    real_save = study_file.save_study

    def save_study(result, path):
        done = real_save(result, path)
        pause()
        return done
    study_file.save_study = save_study

from substruct.cli import main  # noqa: E402

if POINT == "exit":
    import atexit

    atexit.register(pause)  # registered after substruct's own: runs before it
sys.argv = ["substruct", *sys.argv[2:]]
sys.exit(main())
