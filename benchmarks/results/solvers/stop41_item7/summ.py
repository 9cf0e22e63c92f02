import json, sys
s = json.load(open(sys.argv[1] + "/summary.json"))
c = s.get("solver_costs", {})
print(sys.argv[2], s["status"], "wall %.1f ksp %.2f pcsetup %.2f" % (s["wall_time"]["total"], c["KSPSolve"]["time"], c["PCSetUp"]["time"]), "unk", sum(s["dofs"].values()), "steps", s["steps"], "rej", s["rejected_steps"],
      "N", s["snes_iterations"], "K", s["ksp_iterations"], "K/N %.1f" % (s["ksp_iterations"] / max(1, s["snes_iterations"])), " ".join(sys.argv[3:]))
