// Zoltan's geometric partitioners on one process (partition_zoltan.hpp).
#include "parallel/partition_zoltan.hpp"

#include <mpi.h>
#include <zoltan.h>

#include <cstdlib>
#include <stdexcept>
#include <string>

namespace fdem {

namespace {

struct Points {
  int dim, n;
  const double* xyz;
  const float* w;
};

int num_obj(void* data, int* ierr) {
  *ierr = ZOLTAN_OK;
  return static_cast<Points*>(data)->n;
}

void obj_list(void* data, int, int, ZOLTAN_ID_PTR gids, ZOLTAN_ID_PTR lids, int wdim, float* w, int* ierr) {
  const auto* p = static_cast<Points*>(data);
  for (int i = 0; i < p->n; ++i) {
    gids[i] = static_cast<ZOLTAN_ID_TYPE>(i);
    lids[i] = static_cast<ZOLTAN_ID_TYPE>(i);
    if (wdim > 0) w[i] = p->w[i];
  }
  *ierr = ZOLTAN_OK;
}

int num_geom(void* data, int* ierr) {
  *ierr = ZOLTAN_OK;
  return static_cast<Points*>(data)->dim;
}

void geom_multi(void* data, int, int, int n, ZOLTAN_ID_PTR, ZOLTAN_ID_PTR lids, int dim, double* out,
                int* ierr) {
  const auto* p = static_cast<Points*>(data);
  for (int i = 0; i < n; ++i)
    for (int d = 0; d < dim; ++d) out[i * dim + d] = p->xyz[static_cast<size_t>(lids[i]) * p->dim + d];
  *ierr = ZOLTAN_OK;
}

void finalize_mpi() {
  int done = 0;
  MPI_Finalized(&done);
  if (!done) MPI_Finalize();
}

}  // namespace

void zoltan_init() {
  static bool done = false;
  if (done) return;
  int init = 0;
  MPI_Initialized(&init);
  if (!init) {
    MPI_Init(nullptr, nullptr);
    std::atexit(finalize_mpi);
  }
  float version = 0;
  if (Zoltan_Initialize(0, nullptr, &version) != ZOLTAN_OK)
    throw std::runtime_error("Zoltan_Initialize failed");
  done = true;
}

std::vector<int> zoltan_partition(int dim, const std::vector<double>& xyz, const std::vector<float>& weight,
                                  int parts, const std::string& lb_method, double imbalance_tol) {
  zoltan_init();
  Points pts{dim, static_cast<int>(weight.size()), xyz.data(), weight.data()};
  Zoltan_Struct* zz = Zoltan_Create(MPI_COMM_SELF);
  Zoltan_Set_Param(zz, "DEBUG_LEVEL", "0");
  Zoltan_Set_Param(zz, "LB_METHOD", lb_method.c_str());
  Zoltan_Set_Param(zz, "NUM_GID_ENTRIES", "1");
  Zoltan_Set_Param(zz, "NUM_LID_ENTRIES", "1");
  Zoltan_Set_Param(zz, "OBJ_WEIGHT_DIM", "1");
  Zoltan_Set_Param(zz, "NUM_GLOBAL_PARTS", std::to_string(parts).c_str());
  Zoltan_Set_Param(zz, "IMBALANCE_TOL", std::to_string(imbalance_tol).c_str());
  Zoltan_Set_Param(zz, "RETURN_LISTS", "PARTS");
  Zoltan_Set_Num_Obj_Fn(zz, num_obj, &pts);
  Zoltan_Set_Obj_List_Fn(zz, obj_list, &pts);
  Zoltan_Set_Num_Geom_Fn(zz, num_geom, &pts);
  Zoltan_Set_Geom_Multi_Fn(zz, geom_multi, &pts);
  int changes = 0, ngid = 0, nlid = 0, nimp = 0, nexp = 0;
  ZOLTAN_ID_PTR igid = nullptr, ilid = nullptr, egid = nullptr, elid = nullptr;
  int *iproc = nullptr, *ipart = nullptr, *eproc = nullptr, *epart = nullptr;
  const int rc = Zoltan_LB_Partition(zz, &changes, &ngid, &nlid, &nimp, &igid, &ilid, &iproc, &ipart, &nexp,
                                     &egid, &elid, &eproc, &epart);
  std::vector<int> part(pts.n, 0);  // objects not in the export list stay in part 0
  if (rc == ZOLTAN_OK)
    for (int i = 0; i < nexp; ++i) part[elid[i]] = epart[i];
  Zoltan_LB_Free_Part(&igid, &ilid, &iproc, &ipart);
  Zoltan_LB_Free_Part(&egid, &elid, &eproc, &epart);
  Zoltan_Destroy(&zz);
  if (rc != ZOLTAN_OK)
    throw std::runtime_error("Zoltan_LB_Partition (" + lb_method + ") failed with status " +
                             std::to_string(rc));
  return part;
}

}  // namespace fdem
