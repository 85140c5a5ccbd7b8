#pragma once
// Union-find over 0..n-1 with path halving; a set's root is its smallest member (host only: the
// mesh module's body and joint checks, the grain generators, the contact set-up).
#include <vector>

namespace fdem {

struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(int n = 0) : parent(n) {
    for (int i = 0; i < n; ++i) parent[i] = i;
  }
  int find(int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  }
  void join(int a, int b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[a > b ? a : b] = a < b ? a : b;
  }
};

}  // namespace fdem
