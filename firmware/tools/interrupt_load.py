#!/usr/bin/env python3
"""The worst main loop tick with the interrupt load of the robot's real configuration.

    interrupt_load.py BENCH ISR LOAD [BUDGET [--not-met BUILD]]

BENCH: the cycle bench's output (each scenario's worst tick, no interrupts); ISR: bench/isr_bench.c's cycles of each
interrupt handler (`isr <vector> <name> worst <c> mean <c>`); LOAD: the XMEGA model's interrupts in each mode
(`LOAD: <mode> <vector> <per second> <most in a millisecond>`, tests/xmega/test_load.c).

A mode's interrupt load is its interrupts per second times their mean cycles, a share of the CPU; a tick runs that
much longer while they come (its cycles / (1 - share)): the worst tick with interrupts. As a bound, the busiest
millisecond: each vector's most interrupts in a millisecond at its mean cost, plus the one handler whose worst call
exceeds its mean the most, all in one tick. Prints both per scenario and the worst of all but the stress scenario;
with BUDGET (cycles), fails when that is over it. With --not-met BUILD, a build known to miss the budget (recorded
in firmware/README.md), it says so in one line instead of failing.
"""
import re
import sys

MODES = [("idle", "idle"), ("movement", "movement"), ("line following", "line_following"),
         ("teleoperation", "teleoperation"), ("track", "track"), ("Bluetooth", "bluetooth"),
         ("stress", "teleoperation")]


def main():
    bench, isr, load = (open(path).read() for path in sys.argv[1:4])
    budget = int(sys.argv[4]) if len(sys.argv) > 4 else None
    not_met = sys.argv[6] if len(sys.argv) > 6 and sys.argv[5] == "--not-met" else None
    cost = {int(m[0]): (m[1], int(m[2]), int(m[3]))
            for m in re.findall(r"isr (\d+) (\S+) worst (\d+) mean (\d+)", isr)}
    rates = {}
    for mode, vector, per_s, per_ms in re.findall(r"LOAD: (\S+) (\d+) (\d+) (\d+)", load):
        rates.setdefault(mode, {})[int(vector)] = (int(per_s), int(per_ms))
    worst = 0
    for scenario, tick in re.findall(r"^(\S[^:\n]*?(?:: [^:\n]*?)?): worst tick +(\d+) cycles", bench, re.M):
        mode = next(m for prefix, m in MODES if scenario.startswith(prefix))
        missing = [v for v in rates[mode] if v not in cost]
        if missing:
            sys.exit(f"no cycle count for interrupt vectors {missing} (bench/isr_bench.c)")
        bound = sum(per_ms * cost[v][2] for v, (_, per_ms) in rates[mode].items())
        bound += max(cost[v][1] - cost[v][2] for v in rates[mode])
        share = sum(per_s * cost[v][2] for v, (per_s, _) in rates[mode].items()) / 32e6
        total = round(int(tick) / (1 - share))
        print(f"{scenario}:\n    worst tick {int(tick):5d}, interrupts {share * 100:4.1f} % of the CPU: with them "
              f"{total:5d} cycles = {total / 320:4.1f} % (bound, the busiest millisecond's all in it: "
              f"{(int(tick) + bound) / 320:5.1f} %)")
        if not scenario.startswith("stress"):
            worst = max(worst, total)
    print(f"WORST TICK WITH INTERRUPTS (all but the stress scenario) {worst} cycles = {worst / 320:.1f} % "
          f"of the 1 ms budget (goal <= 25 %)")
    if budget is not None and worst > budget and not_met:
        print(f"{not_met} build over its cycle budget: {worst / 320:.1f} % of {budget / 320:.0f} % "
              f"(not met, see firmware/README.md)")
    elif budget is not None and worst > budget:
        sys.exit(f"FAIL: worst tick with interrupts {worst} cycles, over the budget of {budget}")


if __name__ == "__main__":
    main()
