#!/usr/bin/env python3
"""Which code ran alone: a serial-slot profile of a two-thread `umbra bench` run.

Amdahl's serial fraction (`umbra bench --json`, `serial_fraction`) says how much of a frame
did not divide among threads; this says which code that was. Record with call chains, at two
threads, then read the samples here:

    RAYON_NUM_THREADS=2 perf record -F 2000 --call-graph dwarf,32768 -o perf.data \\
        umbra bench SCENE --shadows STAGE --threads 2 --runs 2 --warmup 1
    perf script -i perf.data -F tid,time,ip,sym | python3 tools/serial_slots.py [TOP]

Time is cut into 1 ms slots. A worker thread is busy in a slot when it has a sample outside
rayon's idle loop and the kernel's waiting; a slot in which one worker alone is busy is a
serial slot. The busy worker's samples there are counted by their first three frames in
umbra (leaf first). Samples before the first frame (`render::frame_pass` on a worker), the
scene's loading, are left out; the warm-up frame is not. A parallel loop's last piece, run while the
other thread waits, counts as serial too: for Amdahl's law it is.
"""
import collections
import re
import sys

IDLE = re.compile(
    r"rayon_core::(sleep|registry::WorkerThread::(wait_until|find_work|take_local))|crossbeam"
    r"|futex|sched_yield|syscall|\[unknown\]|_raw_spin|schedule|entry_SYSCALL|pthread_cond"
    r"|__lll|try_to_wake|finish_task_switch"
)
HEADER = re.compile(r"\s*(\d+)\s+([\d.]+):")
FRAME = re.compile(r"\s+[0-9a-f]+\s+(.*?)(?:\s+\((.*)\))?\s*$")


def samples(lines):
    """(thread, time in s, [symbols, leaf first]) for each sample of `perf script`."""
    current = None
    for line in lines:
        head = HEADER.match(line)
        if head and not line.startswith(("\t", " " * 8)):
            if current:
                yield current
            current = (int(head[1]), float(head[2]), [])
            continue
        frame = FRAME.match(line)
        if frame and current:
            current[2].append(frame[1])
    if current:
        yield current


def main():
    top = int(sys.argv[1]) if len(sys.argv) > 1 else 30
    all_samples = list(samples(sys.stdin))
    if not all_samples:
        sys.exit("no samples on standard input (perf script -F tid,time,ip,sym)")
    main_thread = all_samples[0][0]
    slots = collections.defaultdict(lambda: collections.defaultdict(list))
    started = False
    for tid, t, stack in all_samples:
        if tid == main_thread or not stack:
            continue
        started = started or any("render::frame_pass" in s for s in stack)
        if started:
            slots[int(t * 1000)][tid].append(stack)
    if not slots:
        sys.exit("no frame found (no worker sample in render::frame_pass)")
    workers = sorted({tid for slot in slots.values() for tid in slot})
    busy = lambda stacks: [s for s in stacks if not IDLE.search(s[0])]
    serial, counts = collections.Counter(), collections.Counter()
    for k in range(min(slots), max(slots) + 1):
        slot = slots.get(k, {})
        running = [tid for tid in workers if busy(slot.get(tid, []))]
        counts[min(len(running), 2)] += 1
        if len(running) == 1:
            for stack in busy(slot[running[0]]):
                ours = [s for s in stack if s.startswith("umbra::") or "<umbra::" in s]
                serial[" <- ".join(s[:70] for s in ours[:3]) or stack[0][:80]] += 1
    total = counts[1] + counts[2]
    print(f"slots: {counts[1]} ms with one worker busy, {counts[2]} with both "
          f"({100 * counts[1] / max(total, 1):.1f}% serial), {counts[0]} with none")
    n = sum(serial.values())
    for where, c in serial.most_common(top):
        print(f"{100 * c / n:5.1f}% {c:6d}  {where}")


if __name__ == "__main__":
    main()
