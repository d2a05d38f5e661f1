#!/usr/bin/env python3
# Usage: fullspace_block_mesh.py NX NY NZ OUT.msh — the 10 × 10 × 3 cm driven block of examples/verify/febio_block
# with NX×NY×NZ cells, for the preconditioner measurements of docs/results/performance.md (issue 48).
# Port of fullspace::box_tet_mesh (Kuhn split) written as gmsh 2.2 ASCII, the groups as physical points.
import sys
cx, cy, cz = map(int, sys.argv[1:4]); out = sys.argv[4]
size = (0.1, 0.1, 0.03)
nx, ny, nz = cx+1, cy+1, cz+1
idx = lambda i,j,k: i + nx*(j + ny*k)
nodes = []; groups = {g: [] for g in ["all","xmax","xmin","ymax","ymin","zmax","zmin"]}
for k in range(nz):
  for j in range(ny):
    for i in range(nx):
      v = idx(i,j,k); nodes.append((size[0]*i/cx, size[1]*j/cy, size[2]*k/cz)); groups["all"].append(v)
      if i==0: groups["xmin"].append(v)
      if i==cx: groups["xmax"].append(v)
      if j==0: groups["ymin"].append(v)
      if j==cy: groups["ymax"].append(v)
      if k==0: groups["zmin"].append(v)
      if k==cz: groups["zmax"].append(v)
orders = [(0,1,2),(1,2,0),(2,0,1),(0,2,1),(2,1,0),(1,0,2)]
tets = []
for k in range(cz):
  for j in range(cy):
    for i in range(cx):
      for p in range(6):
        at = [i,j,k]; t = [idx(*at)]
        for s in range(3):
          at[orders[p][s]] += 1; t.append(idx(*at))
        if p >= 3: t[2], t[3] = t[3], t[2]
        tets.append(t)
names = list(groups)
with open(out, "w") as f:
  f.write("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n%d\n" % (len(names)+1))
  for n, g in enumerate(names): f.write('0 %d "%s"\n' % (n+1, g))
  f.write('3 %d "volume"\n$EndPhysicalNames\n$Nodes\n%d\n' % (len(names)+1, len(nodes)))
  for v, (x,y,z) in enumerate(nodes): f.write("%d %r %r %r\n" % (v+1, x, y, z))
  f.write("$EndNodes\n$Elements\n")
  total = sum(len(g) for g in groups.values()) + len(tets)
  f.write("%d\n" % total); e = 1
  for n, g in enumerate(names):
    for v in groups[g]: f.write("%d 15 2 %d %d %d\n" % (e, n+1, n+1, v+1)); e += 1
  for t in tets: f.write("%d 4 2 %d 1 %d %d %d %d\n" % (e, len(names)+1, *(a+1 for a in t))); e += 1
  f.write("$EndElements\n")
