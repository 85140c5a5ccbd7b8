# tests/data/bodies/make_meshes.py: writes small Gmsh 2.2 ASCII meshes of crossed-diagonal rectangles (tests/data/bodies)
def crossed(x0, y0, w, h, nx, ny, reg, nodes, tris):
    base = len(nodes)
    idx = {}
    for j in range(ny + 1):
        for i in range(nx + 1):
            idx[(i, j)] = len(nodes); nodes.append((x0 + w * i / nx, y0 + h * j / ny))
    for j in range(ny):
        for i in range(nx):
            c = len(nodes); nodes.append((x0 + w * (i + .5) / nx, y0 + h * (j + .5) / ny))
            a, b, d, e = idx[(i, j)], idx[(i + 1, j)], idx[(i + 1, j + 1)], idx[(i, j + 1)]
            for p, q in ((a, b), (b, d), (d, e), (e, a)): tris.append([p, q, c, reg])

def write(path, nodes, tris, comment):
    with open(path, 'w') as f:
        f.write('$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Comments\n%s\n$EndComments\n' % comment)
        f.write('$PhysicalNames\n2\n2 1 "rock"\n2 2 "weak"\n$EndPhysicalNames\n')
        f.write('$Nodes\n%d\n' % len(nodes))
        for k, (x, y) in enumerate(nodes): f.write('%d %.17g %.17g 0\n' % (k + 1, x, y))
        f.write('$EndNodes\n$Elements\n%d\n' % len(tris))
        for k, (a, b, c, r) in enumerate(tris):
            f.write('%d 2 2 %d %d %d %d %d\n' % (k + 1, r, r, a + 1, b + 1, c + 1))
        f.write('$EndElements\n')

# one body, 100 mm square, 2 x 2 crossed cells ('rock' left column, 'weak' right column),
# the centre node of the lower left cell duplicated and used by one of its four triangles
n, t = [], []
crossed(0, 0, 0.05, 0.1, 1, 2, 1, n, t)
crossed(0.05, 0, 0.05, 0.1, 1, 2, 2, n, t)
# merge the shared column x = 0.05 (second block's left nodes -> first block's right nodes)
import math
m = {}
for i, p in enumerate(n):
    for j in range(i):
        if math.dist(p, n[j]) < 1e-12: m[i] = j; break
keep = [i for i in range(len(n)) if i not in m]
ren = {o: k for k, o in enumerate(keep)}
t = [[ren[m.get(a, a)], ren[m.get(b, b)], ren[m.get(c, c)], r] for a, b, c, r in t]
n = [n[i] for i in keep]
single_n, single_t = list(n), [list(x) for x in t]
ctr = next(i for i, p in enumerate(n) if math.dist(p, (0.025, 0.025)) < 1e-12)
n.append(n[ctr]); t[3][2] = len(n) - 1
write('duplicate_node.msh', n, t,
      'tests/data/bodies: one body whose node at (0.025, 0.025) is duplicated; one triangle uses the copy')
write('one_body.msh', single_n, single_t, 'tests/data/bodies: the same body without the duplicate')
# two bodies side by side, each with its own nodes on the shared edge x = 0.1
n, t = [], []
crossed(0, 0, 0.1, 0.1, 2, 2, 1, n, t)
crossed(0.1, 0, 0.1, 0.1, 2, 2, 2, n, t)
write('touching_bodies.msh', n, t, 'tests/data/bodies: two 100 mm squares touching along x = 0.1, not joined')
# the second body moved 5 mm into the first (and 3 rows so that its left nodes fall inside)
n, t = [], []
crossed(0, 0, 0.1, 0.1, 2, 2, 1, n, t)
crossed(0.095, 0, 0.1, 0.1, 2, 3, 2, n, t)
write('overlap_5mm.msh', n, t, 'tests/data/bodies: two 100 mm squares overlapping by 5 mm in x')
