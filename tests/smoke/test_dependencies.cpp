// One small real call into each dependency of the stack.
#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CLI/CLI.hpp>
#include <Eigen/Sparse>
#include <H5Cpp.h>
#include <arkode/arkode_erkstep.h>
#include <gmsh.h>
#include <gtest/gtest.h>
#include <ida/ida.h>
#include <nlohmann/json.hpp>
#include <nvector/nvector_petsc.h>
#include <nvector/nvector_serial.h>
#include <omp.h>
#include <petscksp.h>
#include <petsctao.h>
#include <spdlog/spdlog.h>
#include <sundials/sundials_context.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>
#include <toml++/toml.h>
#include <vtkNew.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLPolyDataWriter.h>
#include <zip.h>

#include <cmath>
#include <filesystem>
#include <numeric>

namespace {

std::filesystem::path scratch(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / "sflsh_smoke";
  std::filesystem::create_directories(dir);
  return dir / name;
}

}  // namespace

TEST(Smoke, EigenSparseCholesky) {
  Eigen::SparseMatrix<double> a(3, 3);
  a.insert(0, 0) = 4;
  a.insert(1, 1) = 5;
  a.insert(2, 2) = 6;
  a.insert(0, 1) = a.insert(1, 0) = 1;
  a.makeCompressed();
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(a);
  const Eigen::Vector3d x = ldlt.solve(Eigen::Vector3d(1, 2, 3));
  EXPECT_LT((a * x - Eigen::Vector3d(1, 2, 3)).norm(), 1e-12);
}

TEST(Smoke, PetscKspCgAndTao) {
  Mat a;
  Vec x, b;
  KSP ksp;
  const PetscInt n = 10;
  ASSERT_EQ(MatCreateSeqAIJ(PETSC_COMM_SELF, n, n, 3, nullptr, &a), 0);
  for (PetscInt i = 0; i < n; ++i) {
    if (i > 0) MatSetValue(a, i, i - 1, -1.0, INSERT_VALUES);
    MatSetValue(a, i, i, 2.0, INSERT_VALUES);
    if (i < n - 1) MatSetValue(a, i, i + 1, -1.0, INSERT_VALUES);
  }
  MatAssemblyBegin(a, MAT_FINAL_ASSEMBLY);
  MatAssemblyEnd(a, MAT_FINAL_ASSEMBLY);
  MatCreateVecs(a, &x, &b);
  VecSet(b, 1.0);
  KSPCreate(PETSC_COMM_SELF, &ksp);
  KSPSetOperators(ksp, a, a);
  KSPSetType(ksp, KSPCG);
  KSPSetTolerances(ksp, 1e-12, 1e-14, PETSC_DEFAULT, 100);
  ASSERT_EQ(KSPSolve(ksp, b, x), 0);
  KSPConvergedReason reason;
  KSPGetConvergedReason(ksp, &reason);
  EXPECT_GT(reason, 0);
  PetscReal norm;
  VecNorm(x, NORM_INFINITY, &norm);
  EXPECT_NEAR(norm, 15.0, 1e-8);  // max of i(n+1-i)/2 for n = 10
  Tao tao;
  ASSERT_EQ(TaoCreate(PETSC_COMM_SELF, &tao), 0);
  EXPECT_EQ(TaoSetType(tao, TAOBRGN), 0);
  TaoDestroy(&tao);
  KSPDestroy(&ksp);
  VecDestroy(&x);
  VecDestroy(&b);
  MatDestroy(&a);
}

namespace {
int decay(sunrealtype, N_Vector y, N_Vector ydot, void*) {
  NV_Ith_S(ydot, 0) = -NV_Ith_S(y, 0);
  return 0;
}
}  // namespace

TEST(Smoke, SundialsArkodeAndPetscVector) {
  SUNContext ctx;
  ASSERT_EQ(SUNContext_Create(nullptr, &ctx), 0);
  N_Vector y = N_VNew_Serial(1, ctx);
  NV_Ith_S(y, 0) = 1.0;
  void* mem = ERKStepCreate(decay, 0.0, y, ctx);
  ASSERT_NE(mem, nullptr);
  ERKStepSStolerances(mem, 1e-10, 1e-12);
  sunrealtype t = 0.0;
  ASSERT_GE(ERKStepEvolve(mem, 1.0, y, &t, ARK_NORMAL), 0);
  EXPECT_NEAR(NV_Ith_S(y, 0), std::exp(-1.0), 1e-8);
  ERKStepFree(&mem);
  N_VDestroy(y);

  Vec pv;
  VecCreateSeq(PETSC_COMM_SELF, 4, &pv);
  VecSet(pv, 2.0);
  N_Vector wrapped = N_VMake_Petsc(pv, ctx);
  EXPECT_NEAR(N_VDotProd(wrapped, wrapped), 16.0, 1e-12);
  N_VDestroy(wrapped);
  VecDestroy(&pv);
  void* ida = IDACreate(ctx);
  EXPECT_NE(ida, nullptr);
  IDAFree(&ida);
  SUNContext_Free(&ctx);
}

TEST(Smoke, CgalDelaunay) {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  std::vector<K::Point_3> points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
  CGAL::Delaunay_triangulation_3<K> dt(points.begin(), points.end());
  EXPECT_EQ(dt.number_of_vertices(), 5u);
  EXPECT_TRUE(dt.is_valid());
}

TEST(Smoke, GmshBoxTets) {
  gmsh::initialize(0, nullptr, false);
  gmsh::option::setNumber("General.Terminal", 0);
  gmsh::model::add("box");
  gmsh::model::occ::addBox(0, 0, 0, 1, 1, 1);
  gmsh::model::occ::synchronize();
  gmsh::option::setNumber("Mesh.MeshSizeMax", 0.5);
  gmsh::model::mesh::generate(3);
  std::vector<std::size_t> tags, nodes;
  gmsh::model::mesh::getElementsByType(4, tags, nodes);
  EXPECT_GT(tags.size(), 10u);
  gmsh::finalize();
}

TEST(Smoke, VtkWriteRead) {
  const auto path = scratch("smoke.vtp");
  vtkNew<vtkPoints> points;
  points->InsertNextPoint(0, 0, 0);
  points->InsertNextPoint(1, 2, 3);
  vtkNew<vtkPolyData> poly;
  poly->SetPoints(points);
  vtkNew<vtkXMLPolyDataWriter> writer;
  writer->SetFileName(path.c_str());
  writer->SetInputData(poly);
  ASSERT_EQ(writer->Write(), 1);
  vtkNew<vtkXMLPolyDataReader> reader;
  reader->SetFileName(path.c_str());
  reader->Update();
  EXPECT_EQ(reader->GetOutput()->GetNumberOfPoints(), 2);
}

TEST(Smoke, Hdf5WriteRead) {
  const auto path = scratch("smoke.h5");
  {
    H5::H5File file(path.string(), H5F_ACC_TRUNC);
    const hsize_t dims[2] = {2, 3};
    H5::DataSpace space(2, dims);
    const double data[6] = {1, 2, 3, 4, 5, 6};
    file.createDataSet("x", H5::PredType::NATIVE_DOUBLE, space).write(data, H5::PredType::NATIVE_DOUBLE);
  }
  H5::H5File file(path.string(), H5F_ACC_RDONLY);
  double back[6] = {};
  file.openDataSet("x").read(back, H5::PredType::NATIVE_DOUBLE);
  EXPECT_EQ(back[5], 6.0);
}

TEST(Smoke, ConfigAndCliLibraries) {
  const toml::table t = toml::parse("a = 3\n[b]\nc = \"x\"\n");
  EXPECT_EQ(t["a"].value<int>(), 3);
  EXPECT_EQ(nlohmann::json::parse(R"({"k": [1, 2]})")["k"][1], 2);
  CLI::App app;
  int n = 0;
  app.add_option("-n", n);
  const char* argv[] = {"prog", "-n", "7"};
  app.parse(3, const_cast<char**>(argv));
  EXPECT_EQ(n, 7);
  EXPECT_EQ(fmt::format("{:.1f}", 2.25), "2.2");
  spdlog::level::level_enum level = spdlog::level::from_str("warn");
  EXPECT_EQ(level, spdlog::level::warn);
}

TEST(Smoke, LibzipRoundTrip) {
  const auto path = scratch("smoke.zip");
  std::filesystem::remove(path);
  int err = 0;
  zip_t* z = zip_open(path.c_str(), ZIP_CREATE, &err);
  ASSERT_NE(z, nullptr);
  const char payload[] = "hello";
  zip_source_t* src = zip_source_buffer(z, payload, 5, 0);
  ASSERT_GE(zip_file_add(z, "a.txt", src, 0), 0);
  ASSERT_EQ(zip_close(z), 0);
  z = zip_open(path.c_str(), ZIP_RDONLY, &err);
  ASSERT_NE(z, nullptr);
  zip_file_t* f = zip_fopen(z, "a.txt", 0);
  char buf[8] = {};
  EXPECT_EQ(zip_fread(f, buf, 5), 5);
  zip_fclose(f);
  zip_discard(z);
  EXPECT_STREQ(buf, "hello");
}

TEST(Smoke, ThreadsTbbOpenMp) {
  const long tbb_sum = tbb::parallel_reduce(
      tbb::blocked_range<long>(0, 1000), 0L,
      [](const tbb::blocked_range<long>& r, long acc) {
        for (long i = r.begin(); i != r.end(); ++i) acc += i;
        return acc;
      },
      std::plus<long>());
  EXPECT_EQ(tbb_sum, 499500);
  long omp_sum = 0;
#pragma omp parallel for reduction(+ : omp_sum)
  for (long i = 0; i < 1000; ++i) omp_sum += i;
  EXPECT_EQ(omp_sum, 499500);
  EXPECT_GE(omp_get_max_threads(), 1);
}

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  PetscInitialize(&argc, &argv, nullptr, nullptr);
  const int result = RUN_ALL_TESTS();
  PetscFinalize();
  return result;
}
