#!/usr/bin/env bash
# Two `snncc hpo` workers sharing one study in a local PostgreSQL server (the many-machines recipe,
# on one machine). Installs PostgreSQL from the distribution's packages when missing (Debian/Ubuntu,
# needs root), creates a throw-away cluster in a temporary directory, runs two workers against it,
# prints the report and stops the server.
#
#   examples/hpo/postgres_two_workers.sh [DATA_DIR]
#
# DATA_DIR: published Braille files (default: a small SYNTHETIC set made here with `snncc data synth`).
# On several machines: run ONE server (steps 1-3), open it to the network (listen_addresses, pg_hba.conf),
# and start `snncc hpo run NAME --storage postgresql://USER:PASS@HOST:PORT/DB ...` on every machine.
# Environment: TRIALS (default 6), EPOCHS (2), HIDDEN (16), PORT (55432), KEEP=1 keeps the cluster.
set -euo pipefail

TRIALS=${TRIALS:-6}
EPOCHS=${EPOCHS:-2}
HIDDEN=${HIDDEN:-16}
PORT=${PORT:-55432}
WORK=$(mktemp -d /tmp/snncc-hpo-pg.XXXXXX)
chmod 755 "$WORK"

# 1. the server binaries (Debian: /usr/lib/postgresql/<version>/bin)
if ! ls /usr/lib/postgresql/*/bin/initdb >/dev/null 2>&1; then
    if [ "$(id -u)" -ne 0 ]; then echo "PostgreSQL is not installed; run as root or install the postgresql package" >&2; exit 2; fi
    apt-get update -q
    DEBIAN_FRONTEND=noninteractive apt-get install -y -q postgresql
fi
BIN=$(ls -d /usr/lib/postgresql/*/bin | sort -V | tail -1)
echo "PostgreSQL server: $("$BIN/postgres" --version)"
python -c "import psycopg" 2>/dev/null || { echo "the PostgreSQL driver is missing: pip install 'snncc[postgres]'" >&2; exit 2; }

# 2. a throw-away cluster owned by the postgres user (the server refuses to run as root)
as_pg() { if [ "$(id -u)" -eq 0 ]; then su postgres -s /bin/bash -c "$*"; else bash -c "$*"; fi; }
mkdir -p "$WORK/pgdata" "$WORK/run"
[ "$(id -u)" -eq 0 ] && chown postgres "$WORK/pgdata" "$WORK/run"
as_pg "'$BIN/initdb' -D '$WORK/pgdata' -U snncc --auth=trust -E UTF8 >'$WORK/run/initdb.log'"
as_pg "'$BIN/pg_ctl' -D '$WORK/pgdata' -l '$WORK/run/server.log' -o \"-p $PORT -k '$WORK/run' -c listen_addresses=127.0.0.1\" -w start >/dev/null"
stop() {
    as_pg "'$BIN/pg_ctl' -D '$WORK/pgdata' -m fast -w stop >/dev/null" || true
    [ "${KEEP:-0}" = 1 ] || rm -rf "$WORK"
}
trap stop EXIT
as_pg "'$BIN/createdb' -h 127.0.0.1 -p $PORT -U snncc snncc_hpo"
URL="postgresql://snncc@127.0.0.1:$PORT/snncc_hpo"

# 3. data: the caller's, or a small synthetic set
DATA=${1:-}
if [ -z "$DATA" ]; then
    DATA="$WORK/braille"
    snncc data synth -o "$DATA" -n 8 --thresholds 1 --json >/dev/null
    echo "data: SYNTHETIC (snncc data synth -n 8, seed 0)"
fi

# 4. two workers on one study (each trains, compiles for Loihi and estimates energy per trial)
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 NUMBA_NUM_THREADS=1
ARGS=(hpo run pg-demo --storage "$URL" --data "$DATA" --threshold 1 --step both --trials "$TRIALS"
      --epochs "$EPOCHS" --hidden "$HIDDEN" --range time_bin_size=8:10 --range nb_input_copies=1:2
      --objectives pareto --energy-samples 4 --batch-size 64 --dir "$WORK/trials" --quiet --device cpu)
snncc "${ARGS[@]}" >"$WORK/run/worker1.log" 2>&1 &
W1=$!
snncc "${ARGS[@]}" >"$WORK/run/worker2.log" 2>&1 &
W2=$!
status=0
wait $W1 || status=$?
wait $W2 || status=$?
cat "$WORK/run/worker1.log" "$WORK/run/worker2.log"
[ $status -eq 0 ] || { echo "a worker failed ($status)" >&2; exit $status; }

# 5. what happened: every trial once, both workers used, the report
python - "$URL" <<'PY'
import collections, sys
import optuna
optuna.logging.set_verbosity(optuna.logging.ERROR)
url = sys.argv[1]
for name in ("pg-demo", "pg-demo-grid"):
    trials = optuna.load_study(study_name=name, storage=url).trials
    states = collections.Counter(t.state.name for t in trials)
    workers = collections.Counter(t.user_attrs.get("worker", "?").rsplit(":", 1)[-1] for t in trials)
    params = {tuple(sorted(t.params.items())) for t in trials if t.state.name == "COMPLETE"}
    print(f"{name}: {dict(states)}; trials per worker process {dict(workers)}; "
          f"{len(params)} distinct parameter sets among {states['COMPLETE']} complete")
    assert states["COMPLETE"] == len(params), "a trial ran twice"
PY
snncc hpo report pg-demo --storage "$URL" -o "$WORK/run/pg-demo-front.png"
echo "recipe OK (server $("$BIN/postgres" --version | awk '{print $3}'), storage $URL)"
