#include "scratch_dir.hpp"

#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/interrupt_cleanup.hpp>
#include <sflsh/core/run_folder.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/core/vtk_io.hpp>

#include <gmock/gmock.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>

namespace sflsh {

TEST(AtomicFile, FailedWriterLeavesTargetUntouched) {
  const auto dir = sflsh::testing::scratch_dir();
  write_text_atomically(dir / "a.txt", "first");
  EXPECT_THROW(write_atomically(dir / "a.txt",
                                [](const std::filesystem::path& tmp) {
                                  std::ofstream(tmp) << "partial";
                                  throw_error("writer failed");
                                }),
               Error);
  std::ifstream in(dir / "a.txt");
  std::string content;
  in >> content;
  EXPECT_EQ(content, "first");
  EXPECT_EQ(sflsh::testing::count_entries(dir), 1u);  // no temporary left behind
}

TEST(RunFolder, NothingAppearsUntilCommit) {
  const auto scratch = sflsh::testing::scratch_dir();
  const auto dir = scratch / "run";
  {
    RunFolder run(dir);
    write_text_atomically(run.stage("x.txt"), "x");
    write_text_atomically(run.stage("sub/y.txt"), "y");
    EXPECT_FALSE(std::filesystem::exists(dir / "x.txt"));
    EXPECT_EQ(run.staging().parent_path(), dir.parent_path());  // beside DIR, never inside the user's folder
    // destroyed without commit: as if the run failed
  }
  EXPECT_FALSE(std::filesystem::exists(dir));  // a failed run creates no (empty) output folder
  EXPECT_EQ(sflsh::testing::count_entries(scratch), 0u);
  {
    RunFolder run(dir);
    write_text_atomically(run.stage("x.txt"), "x");
    write_text_atomically(run.stage("sub/y.txt"), "y");
    run.commit();
  }
  EXPECT_TRUE(std::filesystem::exists(dir / "x.txt"));
  EXPECT_TRUE(std::filesystem::exists(dir / "sub/y.txt"));
  EXPECT_EQ(sflsh::testing::count_entries(dir), 3u);      // x.txt, sub, sub/y.txt
  EXPECT_EQ(sflsh::testing::count_entries(scratch), 4u);  // and no staging folder beside it
  {                           // into an existing folder: files replaced one by one, others kept
    RunFolder run(dir / "");  // a trailing separator names the same folder
    write_text_atomically(run.stage("x.txt"), "x2");
    run.commit();
  }
  std::ifstream in(dir / "x.txt");
  std::string content;
  in >> content;
  EXPECT_EQ(content, "x2");
  EXPECT_TRUE(std::filesystem::exists(dir / "sub/y.txt"));
}

TEST(RunFolder, RelativeNamesAndDotWork) {
  const auto scratch = sflsh::testing::scratch_dir();
  const auto cwd = std::filesystem::current_path();
  std::filesystem::current_path(scratch);
  for (const char* name : {"run", "./run2", "sub/run3", "sub/../run4/"}) {
    RunFolder run(name);
    write_text_atomically(run.stage("x.txt"), "x");
    run.commit();
  }
  {
    RunFolder run(".");  // the current folder itself: files are moved into it
    write_text_atomically(run.stage("y.txt"), "y");
    run.commit();
  }
  std::filesystem::current_path(cwd);
  for (const char* file : {"run/x.txt", "run2/x.txt", "sub/run3/x.txt", "run4/x.txt", "y.txt"})
    EXPECT_TRUE(std::filesystem::exists(scratch / file)) << file;
}

TEST(RunFolder, FailedRunRemovesTheParentsItCreated) {
  const auto scratch = sflsh::testing::scratch_dir();
  { RunFolder run(scratch / "a" / "b" / "run"); }
  EXPECT_FALSE(std::filesystem::exists(scratch / "a"));
  {
    RunFolder run(scratch / "a" / "b" / "run");
    write_text_atomically(run.stage("x.txt"), "x");
    run.commit();
  }
  EXPECT_TRUE(std::filesystem::exists(scratch / "a" / "b" / "run" / "x.txt"));
}

TEST(RunFolder, RefusesAFileAsFolder) {
  const auto scratch = sflsh::testing::scratch_dir();
  write_text_atomically(scratch / "file", "x");
  EXPECT_THAT([&] { RunFolder run(scratch / "file"); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr("is not a folder")));
}

/// A pid that belonged to a process which has ended.
long dead_pid() {
  const pid_t child = ::fork();
  if (child == 0) std::_Exit(0);
  int status = 0;
  ::waitpid(child, &status, 0);
  return static_cast<long>(child);
}

TEST(RunFolder, RemovesStagingFoldersOfDeadProcesses) {
  const auto scratch = sflsh::testing::scratch_dir();
  const long dead = dead_pid();
  const auto stale = scratch / fmt::format(".other.staging-{}", dead);
  const auto stale_old_layout = scratch / "run" / fmt::format(".staging-{}", dead);
  const auto alive = scratch / fmt::format(".busy.staging-{}", static_cast<long>(::getppid()));  // a live process
  for (const auto& p : {stale, stale_old_layout, alive}) {
    std::filesystem::create_directories(p);
    write_text_atomically(p / "frame.vtp", "partial");
  }
  { RunFolder run(scratch / "run"); }
  EXPECT_FALSE(std::filesystem::exists(stale));
  EXPECT_FALSE(std::filesystem::exists(stale_old_layout));
  EXPECT_TRUE(std::filesystem::exists(alive));
}

TEST(InterruptCleanup, RemovesATreeWithSignalSafeCalls) {
  const auto scratch = sflsh::testing::scratch_dir();
  const auto tree = scratch / "tree";
  for (int i = 0; i < 7; ++i) std::filesystem::create_directories(tree / fmt::format("d{}", i) / "deeper");
  for (int i = 0; i < 300; ++i)
    write_text_atomically(tree / fmt::format("d{}", i % 7) / fmt::format("f{}.txt", i), "x");
  EXPECT_TRUE(remove_tree_signal_safe(tree.c_str()));
  EXPECT_FALSE(std::filesystem::exists(tree));
  EXPECT_TRUE(remove_tree_signal_safe((scratch / "missing").c_str()));
}

TEST(VtkOutput, SurfaceAndTetsReadBackWithVtkReaders) {
  const auto dir = sflsh::testing::scratch_dir();
  sflsh::vtk::Points points(4, 3);
  points << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  sflsh::vtk::Cells triangles(4, 3);
  triangles << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3;
  sflsh::vtk::Fields fields;
  fields.point_data.push_back({"displacement", Eigen::MatrixXd::Constant(4, 3, 0.5), false});
  fields.point_data.push_back({"label", (Eigen::MatrixXd(4, 1) << 0, 1, 2, 3).finished(), true});
  sflsh::vtk::write_surface(dir / "s.vtp", points, triangles, fields);
  EXPECT_TRUE(sflsh::vtk::read_points(dir / "s.vtp").isApprox(points));
  EXPECT_THAT(sflsh::vtk::read_point_array_names(dir / "s.vtp"),
              ::testing::ElementsAre("displacement", "label", "Normals"));
  EXPECT_EQ(sflsh::vtk::read_point_array(dir / "s.vtp", "label")(3, 0), 3.0);

  sflsh::vtk::Cells tet(1, 4);
  tet << 0, 1, 2, 3;
  sflsh::vtk::write_unstructured(dir / "t.vtu", points, tet, fields);
  EXPECT_TRUE(sflsh::vtk::read_points(dir / "t.vtu").isApprox(points));
  EXPECT_TRUE(
      sflsh::vtk::read_point_array(dir / "t.vtu", "displacement").isApprox(Eigen::MatrixXd::Constant(4, 3, 0.5)));

  sflsh::vtk::PvdSeries series(dir / "series.pvd");
  series.add(0.0, "s.vtp");
  series.add(1.0 / 60.0, "t.vtu");
  series.write();
  std::ifstream in(dir / "series.pvd");
  const std::string xml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_THAT(xml, ::testing::HasSubstr("timestep=\"0.0166666667\""));
  EXPECT_THAT(xml, ::testing::HasSubstr("file=\"t.vtu\""));
}

TEST(VtkOutput, RefusesNonFiniteDataAndWritesNothing) {
  const auto dir = sflsh::testing::scratch_dir();
  sflsh::vtk::Points points = sflsh::vtk::Points::Zero(3, 3);
  points(1, 0) = std::nan("");
  sflsh::vtk::Cells tri(1, 3);
  tri << 0, 1, 2;
  EXPECT_THROW(sflsh::vtk::write_surface(dir / "bad.vtp", points, tri), Error);
  sflsh::vtk::Points ok = sflsh::vtk::Points::Identity(3, 3);
  sflsh::vtk::Fields fields;
  fields.point_data.push_back({"short", Eigen::MatrixXd::Zero(2, 1), false});
  EXPECT_THROW(sflsh::vtk::write_surface(dir / "bad.vtp", ok, tri, fields), Error);
  tri(0, 2) = 7;
  EXPECT_THROW(sflsh::vtk::write_surface(dir / "bad.vtp", ok, tri), Error);
  EXPECT_EQ(sflsh::testing::count_entries(dir), 0u);
}

TEST(Summary, JsonRoundTripAndParseErrors) {
  const auto dir = sflsh::testing::scratch_dir();
  const char* argv[] = {"sflsh", "motion", "export"};
  nlohmann::json s = summary_header("motion export", 3, argv);
  s["frames"] = 12;
  write_json(dir / "summary.json", s);
  EXPECT_EQ(read_json(dir / "summary.json")["frames"], 12);
  EXPECT_EQ(read_json(dir / "summary.json")["command"], "motion export");
  std::ofstream(dir / "bad.json") << "{\"a\": ";
  EXPECT_THAT([&] { read_json(dir / "bad.json"); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr("bad.json: invalid JSON")));
}

// write_summary: the run time under its one name, timings.total_seconds, beside the command's other timings, the
// older names a command asks for with the same value, and summary.json staged with the run's other files.
TEST(Summary, WriteSummarySetsTheRunTimeAndItsAliases) {
  const auto scratch = sflsh::testing::scratch_dir();
  const char* argv[] = {"sflsh", "mesh"};
  nlohmann::json s = summary_header("mesh", 2, argv);
  s["timings"] = {{"fit_seconds", 1.5}};
  s["timings_s"] = {{"retarget", 0.25}};
  {
    RunFolder run(scratch / "run");
    write_summary(run, s, 2.5,
                  {.wall_time_s = true, .seconds = true, .timings_s_total = true, .timings_wall_seconds = true});
    EXPECT_FALSE(std::filesystem::exists(scratch / "run" / "summary.json"));  // staged until commit()
    run.commit();
  }
  const nlohmann::json written = read_json(scratch / "run" / "summary.json");
  EXPECT_EQ(written, s);  // the caller keeps the summary that was written
  EXPECT_EQ(written["command"], "mesh");
  EXPECT_EQ(written["timings"]["total_seconds"], 2.5);
  EXPECT_EQ(written["timings"]["fit_seconds"], 1.5);  // the other timings are kept
  EXPECT_EQ(written["timings_s"]["retarget"], 0.25);
  EXPECT_EQ(written["wall_time_s"], 2.5);
  EXPECT_EQ(written["seconds"], 2.5);
  EXPECT_EQ(written["timings_s"]["total"], 2.5);
  EXPECT_EQ(written["timings"]["wall_seconds"], 2.5);

  // Without aliases only timings.total_seconds names the run time.
  nlohmann::json plain = summary_header("body export", 2, argv);
  {
    RunFolder run(scratch / "plain");
    write_summary(run, plain, 0.75);
    run.commit();
  }
  const nlohmann::json only = read_json(scratch / "plain" / "summary.json");
  EXPECT_EQ(only["timings"], (nlohmann::json{{"total_seconds", 0.75}}));
  for (const char* alias : {"wall_time_s", "seconds", "timings_s"}) EXPECT_FALSE(only.contains(alias)) << alias;
}

}  // namespace sflsh
