#!/usr/bin/env python3
"""The SQ table of the hard surfaces (../shared/data/bsplines/hard) at the defaults and at the
paper's Fig. 19 settings (θ 15°, α 45°): start, singular vertices, coverage, exactness, node axes,
support planes, crossing arcs, distance, exit and time, read from each run's report.json.

    python3 tests/sq_hard_table.py target/release/spherical-faces [FILES...]

With --corpus, every FILE runs at the defaults only, two at a time, and the table ends with the
counts (meets every guarantee, misses by guarantee, refusals):

    python3 tests/sq_hard_table.py target/release/spherical-faces --corpus ../shared/data/bsplines/hard/corpus/*.json
"""
import collections, concurrent.futures, json, os, subprocess, sys, tempfile, time

HARD = os.path.join(os.path.dirname(__file__), '..', '..', 'shared', 'data', 'bsplines', 'hard')
NAMES = ['tunnel_bulged', 'roof_rough', 'tower_top', 'wavy_canopy', 'bezier_blob', 'revolved_bell', 'umbilic_dome']
SETTINGS = [('default', []), ('fig19', ['--theta', '15', '--alpha', '45'])]


def guarantee(report, name):
    for g in report.get('guarantees', []):
        if g['name'] == name:
            return g
    return None


def fmt(x, spec):
    return '—' if x is None else format(x, spec)


def row(binary, path, extra):
    with tempfile.TemporaryDirectory(prefix='sqhard') as out:
        return run_in(binary, path, extra, out)


def run_in(binary, path, extra, out):
    t0 = time.time()
    p = subprocess.run([binary, 'sq', path, '--out', out, '-q', '--formats', 'glb'] + extra, capture_output=True, text=True)
    dt = time.time() - t0
    rp = os.path.join(out, 'report.json')
    if not os.path.exists(rp):
        return [f'exit {p.returncode}', p.stderr.strip().splitlines()[-1][:90] if p.stderr.strip() else '']
    r = json.load(open(rp))
    sq = r['sq']
    m = sq.get('sq_mesh') or {}
    g = lambda n: (guarantee(r, n) or {}).get('measured')
    q = sq.get('quad_mesh') or {}
    by = lambda d: ', '.join(f'{k}: {v}' for k, v in sorted(d.items())) or 'none'
    sing = (f"{q['follows'].replace('_', ' ')}; field {by(q.get('singular_points_by_valence', {}))}; mesh {by(q.get('singular_vertices_by_valence', {}))}"
            if 'follows' in q else None)
    missed = [x['name'] for x in r.get('guarantees', []) if not x['holds']]
    return [
        sq['congruence']['start'],
        str(sing) if sing is not None else '—',
        fmt(g('coverage'), '.3f'),
        fmt(g('max_vertex_sphere_residual'), '.1e'),
        fmt(g('max_axis_normal_angle_deg'), '.1f'),
        fmt(g('min_support_plane_angle_deg'), '.1f'),
        ', '.join(f'{m}: {g(f"min_support_plane_angle_valence_{m}_deg"):.1f}' for m in (3, 5) if g(f'min_support_plane_angle_valence_{m}_deg') is not None) or '—',
        fmt(g('panels_with_crossing_arcs'), '.0f'),
        fmt(g('max_distance_to_reference'), '.2e'),
        str(p.returncode),
        f'{r["timings_ms"]["total"] / 1000:.1f}',
        ', '.join(missed),
    ]


HEADER = ('| surface | setting | start | quad mesh follows; singular points, vertices (valence: count) | coverage | vertex–sphere | axes ° | planes ° | planes at singular ° | crossing | distance | exit | s | missed |\n'
          '|---|---|---|---|---|---|---|---|---|---|---|---|---|---|')


def corpus(binary, files):
    print(HEADER)
    misses, exits = collections.Counter(), collections.Counter()
    with concurrent.futures.ThreadPoolExecutor(2) as pool:
        for f, cells in zip(files, pool.map(lambda f: row(binary, f, []), files)):
            print(f'| {os.path.basename(f)[:-5]} | default | ' + ' | '.join(cells) + ' |', flush=True)
            exits[cells[-3] if len(cells) > 2 else cells[0]] += 1
            for m in (cells[-1].split(', ') if len(cells) > 2 and cells[-1] else []):
                misses[m] += 1
    print(f'\n{len(files)} runs; exits: {dict(sorted(exits.items()))}; misses by guarantee: {dict(misses.most_common())}')


def main():
    binary = sys.argv[1]
    if sys.argv[2:3] == ['--corpus']:
        return corpus(binary, sys.argv[3:])
    files = sys.argv[2:] or [os.path.join(HARD, n + '.json') for n in NAMES]
    print(HEADER)
    for f in files:
        for name, extra in SETTINGS:
            cells = row(binary, f, extra)
            print(f'| {os.path.basename(f)[:-5]} | {name} | ' + ' | '.join(cells) + ' |', flush=True)


if __name__ == '__main__':
    main()
