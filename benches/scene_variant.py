"""Write a variant of a scene file: `python3 benches/scene_variant.py SCENE OUT key=value ...`.

A bare key replaces the whole [approximation] table by the keys given (`basis="phs"`,
`degree=4`); `table.key=value` sets one key of another table (`nodes.spacing=0.02`),
adding it if absent. Values are TOML literals (quote strings). `-table` drops a whole
table (`-nodes.refine`: uniform spacing).
"""
import sys
src, out = sys.argv[1], sys.argv[2]
edits, dropped = {}, {a[1:] for a in sys.argv[3:] if a.startswith('-')}
for kv in (a for a in sys.argv[3:] if not a.startswith('-')):
    k, v = kv.split('=', 1)
    table, key = (k.rsplit('.', 1) if '.' in k else ('approximation', k))
    edits.setdefault(table, {})[key] = v
lines = open(src).read().split('\n')
out_lines, table, seen = [], None, set()
def flush(t):
    if t in dropped:
        return
    for k, v in edits.get(t, {}).items():
        if (t, k) not in seen:
            out_lines.append(f'{k} = {v}')
            seen.add((t, k))
for line in lines:
    st = line.strip()
    if st.startswith('[') and not st.startswith('[['):
        flush(table)
        table = st.strip('[]')
        if table in dropped:
            continue
    if table in dropped and not st.startswith('[['):
        continue
    elif st.startswith('[['):
        flush(table)
        table = None
    if table == 'approximation' and 'approximation' in edits and not st.startswith('['):
        continue  # the approximation table is replaced whole
    key = st.split('=')[0].strip() if '=' in st else None
    if table in edits and key in edits[table] and table != 'approximation':
        out_lines.append(f'{key} = {edits[table][key]}')
        seen.add((table, key))
        continue
    out_lines.append(line)
flush(table)
for t, kv in edits.items():
    if t not in dropped and any((t, k) not in seen for k in kv):
        out_lines.append(f'\n[{t}]')
        flush(t)
open(out, 'w').write('\n'.join(out_lines) + '\n')
