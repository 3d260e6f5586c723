# Sourced by the bench scripts: `cores`, the cores this process may run on, in taskset's
# numbering (a cpuset may leave out core 0, so 0..nproc-1 is not assumed).
read -r -a cores <<< "$(/usr/bin/python3 -c 'import os; print(*sorted(os.sched_getaffinity(0)))')"
