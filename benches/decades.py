"""The cheapest run of each sweep that reached each decade of exact e_inf(sigma), as the
README's Markdown table: `python3 benches/decades.py [SCENE ...]` after
`bash benches/tradeoff.sh` (reads output/bench_tradeoff/<scene>/tradeoff.json)."""
import json
import sys

scenes = sys.argv[1:] or ["cantilever", "manufactured_dirichlet", "manufactured_traction", "lame", "kirsch", "flamant"]
decades = [1e-2, 1e-3, 1e-4, 1e-5, 1e-6]
print("| scene | runs (s) | " + " | ".join(f"<= {d:.0e}".replace("e-0", "e-") for d in decades) + " |")
print("|---|---|" + "---|" * len(decades))
for scene in scenes:
    s = json.load(open(f"output/bench_tradeoff/{scene}/tradeoff.json"))
    ok = [r for r in s["runs"] if r["status"] == "ok" and (r.get("exact") or {}).get("e_inf_sigma") is not None]
    cells, previous = [], None
    for d in decades:
        reach = [r for r in ok if r["exact"]["e_inf_sigma"] <= d]
        best = min(reach, key=lambda r: r["seconds"]) if reach else None
        if best is None:
            cells.append("-")
        elif best is previous:
            cells.append("same")
        else:
            cells.append(f"{best['family']}, {best['nodes']} nodes, {best['seconds']:.3f} s ({best['exact']['e_inf_sigma']:.1e})")
        previous = best
    print(f"| {scene} | {len(ok)} ({s['elapsed_s']:.0f}) | " + " | ".join(cells) + " |")
