# shellcheck shell=bash disable=SC2034 # pinned and pin_note are for the sourcing script
# The bench scripts' --pin CPUS option (issue 39), sourced by each: every timed command, on both
# sides (splash and its peer, or the old and the new binary), runs under `taskset -c CPUS`, by
# default 0,1 (a farm node gives a job no idle core); "none" runs them unpinned. Untimed steps
# (builds, input preparation, quality scoring) stay unpinned.
#
#   pin_setup CPUS   checks CPUS (taskset on the PATH; a list such as 0,1 or 0-3,6 whose every
#                    CPU exists and is available to this job) or exits 2; then sets `pinned`,
#                    the command prefix (taskset -c CPUS, or nothing for "none"), and
#                    `pin_note`, for the tables' header lines: "CPU AMD EPYC, 2 available,
#                    pinned to 0,1" or "CPU AMD EPYC, 2 available, unpinned".
#
# Run a timed command as ${pinned[@]+"${pinned[@]}"} COMMAND ARGS….

# The CPUs of a list (0,1 or 0-3,6), one a line; "bad" for a part that is no CPU or range.
pin_cpus() {
    awk -v list="$1" 'BEGIN {
        n = split(list, part, ",")
        if (n == 0) print "bad"
        for (i = 1; i <= n; i++) {
            if (part[i] ~ /^[0-9]+$/) print part[i] + 0
            else if (part[i] ~ /^[0-9]+-[0-9]+$/) {
                split(part[i], r, "-")
                if (r[1] + 0 > r[2] + 0) print "bad"
                for (c = r[1] + 0; c <= r[2] + 0; c++) print c
            } else print "bad"
        }
    }'
}

pin_setup() {
    local pin=$1 allowed cpu model count
    allowed=$(sed -n 's/^Cpus_allowed_list:[[:space:]]*//p' /proc/self/status)
    count=$(pin_cpus "$allowed" | grep -c '^[0-9]')
    model=$(sed -n 's/^model name[[:space:]]*:[[:space:]]*//p' /proc/cpuinfo | head -1)
    model=${model:-$(uname -m), model unknown}
    pinned=()
    if [ "$pin" = none ]; then
        pin_note="CPU $model, $count available, unpinned"
        return
    fi
    command -v taskset >/dev/null ||
        { echo "--pin $pin needs taskset (util-linux); --pin none runs unpinned" >&2; exit 2; }
    for cpu in $(pin_cpus "$pin"); do
        [ "$cpu" != bad ] ||
            { echo "--pin $pin: not a CPU list (e.g. 0,1 or 0-3; none for unpinned)" >&2; exit 2; }
        pin_cpus "$allowed" | grep -qx "$cpu" ||
            { echo "--pin $pin: CPU $cpu does not exist or is not available to this job (available: $allowed)" >&2; exit 2; }
    done
    taskset -c "$pin" true ||
        { echo "--pin $pin: taskset -c $pin fails here" >&2; exit 2; }
    pinned=(taskset -c "$pin")
    pin_note="CPU $model, $count available, pinned to $pin"
}

# Takes --pin CPUS out of the arguments wherever it stands: sets `pin` (default 0,1) and `args`,
# the others in order (then: set -- ${args[@]+"${args[@]}"}; pin_setup "$pin").
pin_args() {
    pin=0,1 args=()
    while [ $# -gt 0 ]; do
        if [ "$1" = --pin ]; then
            [ $# -ge 2 ] || { echo "--pin needs CPUS (e.g. 0,1, or none)" >&2; exit 2; }
            pin=$2
            shift 2
        else
            args+=("$1")
            shift
        fi
    done
}
