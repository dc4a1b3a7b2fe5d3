#!/usr/bin/env python3
"""Symbolises the stacks scripts/wall_sampler/wall_sampler.c recorded: the leaf functions and
each function's inclusive share of the samples (a function counted once a sample).

Usage: python3 symbolise.py SAMPLES [NAME=PATH ...] [focus=TEXT]
  NAME=PATH  the module NAME (its file name in the samples' /proc/self/maps, e.g. fragg_map or
             liblmdb.so.0.0.0) is read from PATH here (an unstripped copy of the program);
             only modules named so are symbolised (another machine's libc is not this one's),
             the others are shown by file name.
  focus=TEXT only the samples with a frame containing TEXT, each shown as the frame it called
             and its leaf.
Needs addr2line (binutils).
"""
import collections
import os
import subprocess
import sys


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    text = open(sys.argv[1]).read().split('\nMAPS\n')
    samples = [[int(a, 16) for a in line.split()] for line in text[0].splitlines() if line.strip()]
    maps = []
    for line in text[1].splitlines() if len(text) > 1 else []:
        p = line.split()
        if len(p) < 6 or 'x' not in p[1]:
            continue
        lo, hi = [int(x, 16) for x in p[0].split('-')]
        maps.append((lo, hi, int(p[2], 16), p[5]))
    args = sys.argv[2:]
    paths = dict(a.split('=', 1) for a in args if '=' in a and not a.startswith('focus='))
    focus = next((a[6:] for a in args if a.startswith('focus=')), None)

    def locate(a):
        for lo, hi, off, path in maps:
            if lo <= a < hi:
                return path, a - lo + off
        return None, a

    offsets = collections.defaultdict(set)
    for s in samples:
        for a in s:
            m, o = locate(a)
            if m:
                offsets[m].add(o)
    names = {}
    for m, offs in offsets.items():
        path = paths.get(os.path.basename(m))
        if not path or not os.path.exists(path):
            continue
        offs = sorted(offs)
        out = subprocess.run(['addr2line', '-f', '-C', '-e', path] + [hex(o) for o in offs],
                             capture_output=True, text=True).stdout.splitlines()
        for i, o in enumerate(offs):
            names[(m, o)] = out[2 * i][:110] if 2 * i < len(out) else '?'
    leaf, incl = collections.Counter(), collections.Counter()
    for s in samples:
        frames = []
        for a in s[2:]:  # the handler and the signal trampoline
            m, o = locate(a)
            frames.append(names.get((m, o), os.path.basename(m) if m else '?'))
        if not frames:
            continue
        if focus:
            hits = [i for i, f in enumerate(frames) if focus in f]
            if not hits:
                continue
            k = max(hits)
            below = frames[k - 1] if k > 0 else '(self)'
            leaf[below[:100] + '  <= leaf ' + frames[0][:50]] += 1
        else:
            leaf[frames[0]] += 1
        for f in set(frames):
            incl[f] += 1
    n = len(samples)
    print('samples', n)
    print('-- leaf')
    for k, v in leaf.most_common(30):
        print(f'{100 * v / n:6.1f}% {k}')
    print('-- inclusive')
    for k, v in incl.most_common(45):
        print(f'{100 * v / n:6.1f}% {k}')


if __name__ == '__main__':
    main()
