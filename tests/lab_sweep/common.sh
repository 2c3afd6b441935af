# Sourced by the ./lab sweep tests with their arguments RAYLAB_TOOL REPO_DIR WORK_DIR: sets tool,
# repo and work (absolute paths), lab (the repo's ./lab running that tool) and same_rows A B (the
# rows of two runs CSVs equal, timing columns aside: same_rows.py).
[ $# -eq 3 ] || { echo "usage: $0 RAYLAB_TOOL REPO_DIR WORK_DIR" >&2; exit 2; }
lab_sweep_tests=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
tool=$(realpath -e -- "$1")
repo=$(realpath -e -- "$2")
work=$(realpath -m -- "$3")
lab=(env "RAYLAB_TOOL=$tool" "$repo/lab")
same_rows() { python3 "$lab_sweep_tests/same_rows.py" "$@"; }
