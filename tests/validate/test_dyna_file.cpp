// DYNA HDF5 files: the writer/reader round trip, float32 input as h5py writes it, attributes, listing, and
// one clear one-line error per kind of malformed file.
#include "error_of.hpp"
#include "scratch_dir.hpp"
#include "synthetic_body.hpp"

#include <sflsh/validate/dyna_file.hpp>

#include <H5Cpp.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <limits>

namespace sflsh::validate {
namespace {

using sflsh::testing::error_of;
using ::testing::HasSubstr;
using ::testing::Not;

RowMatrixX3i small_faces() {
  RowMatrixX3i f(2, 3);
  f << 0, 1, 2, 1, 3, 2;
  return f;
}

DynaSequence ramp(const std::string& key, int vertices, int frames, double offset = 0.0) {
  DynaSequence s;
  s.key = key;
  for (int t = 0; t < frames; ++t) {
    RowMatrixX3d f(vertices, 3);
    for (int v = 0; v < vertices; ++v)
      for (int c = 0; c < 3; ++c) f(v, c) = offset + 100.0 * t + 10.0 * v + c + 0.125;
    s.frames.push_back(f);
  }
  return s;
}

/// Writes a raw HDF5 file: `faces` (unless empty) and one dataset of arbitrary shape and type.
void write_raw(const std::filesystem::path& path, const RowMatrixX3i& faces, const std::string& name,
               const std::vector<hsize_t>& dims, const std::vector<double>& values,
               const H5::PredType& file_type = H5::PredType::IEEE_F64LE) {
  H5::H5File file(path.string(), H5F_ACC_TRUNC);
  if (faces.rows() > 0) {
    const hsize_t fd[2] = {static_cast<hsize_t>(faces.rows()), 3};
    file.createDataSet("faces", H5::PredType::STD_I64LE, H5::DataSpace(2, fd))
        .write(faces.data(), H5::PredType::NATIVE_INT);
  }
  if (!name.empty())
    file.createDataSet(name, file_type, H5::DataSpace(static_cast<int>(dims.size()), dims.data()))
        .write(values.data(), H5::PredType::NATIVE_DOUBLE);
}

TEST(DynaFile, WriterAndReaderRoundTripWithAttributes) {
  const auto dir = sflsh::testing::scratch_dir();
  const auto path = dir / "dyna_female.h5";
  Attributes file_attributes;
  file_attributes.strings["gender"] = "female";
  file_attributes.numbers["fps"] = {120.0};
  DynaSequence a = ramp("50004_jiggle_on_toes", 4, 3);
  a.attributes.numbers["beta"] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
  a.attributes.strings["source"] = "synthetic";
  DynaSequence b = ramp("50004_shake_hips", 4, 5, 7.0);
  b.fps = 30.0;
  const DynaSequence c = ramp("50020_one_leg_jump", 4, 2);
  write_dyna_file(path, small_faces(), {a, b, c}, file_attributes);

  const DynaFile file(path);
  EXPECT_EQ(file.keys(), (std::vector<std::string>{"50004_jiggle_on_toes", "50004_shake_hips", "50020_one_leg_jump"}));
  EXPECT_EQ(file.subjects(), (std::vector<std::string>{"50004", "50020"}));
  EXPECT_EQ(file.sequences("50004"), (std::vector<std::string>{"jiggle_on_toes", "shake_hips"}));
  EXPECT_EQ(file.num_vertices(), 4);
  EXPECT_EQ(file.faces(), small_faces());
  EXPECT_EQ(file.attributes().strings.at("gender"), "female");
  EXPECT_EQ(file.info("50004_shake_hips").frames, 5);
  EXPECT_EQ(file.info("50004_shake_hips").dtype, "float64");

  const DynaSequence ra = file.read("50004_jiggle_on_toes");
  ASSERT_EQ(ra.num_frames(), 3);
  for (int t = 0; t < 3; ++t)
    EXPECT_EQ(ra.frames[static_cast<std::size_t>(t)], a.frames[static_cast<std::size_t>(t)]);  // float64: bit-exact
  EXPECT_EQ(ra.attributes.numbers.at("beta"), a.attributes.numbers.at("beta"));
  EXPECT_EQ(ra.attributes.strings.at("source"), "synthetic");
  EXPECT_EQ(ra.fps, 120.0);                            // from the file attribute
  EXPECT_EQ(file.read("50004_shake_hips").fps, 30.0);  // the dataset's own attribute wins
  EXPECT_EQ(file.read("50004_shake_hips").frames[4], b.frames[4]);
}

TEST(DynaFile, ReadsFloat32VertexMajorLayoutAndDefaultsTo60Fps) {
  const auto path = sflsh::testing::scratch_dir() / "f32.h5";
  // (V, 3, T) = (4, 3, 2): value = 10v + c + 0.5t, exactly representable in float32.
  std::vector<double> values;
  for (int v = 0; v < 4; ++v)
    for (int c = 0; c < 3; ++c)
      for (int t = 0; t < 2; ++t) values.push_back(10.0 * v + c + 0.5 * t);
  write_raw(path, small_faces(), "50002_hips", {4, 3, 2}, values, H5::PredType::IEEE_F32LE);
  const DynaFile file(path);
  EXPECT_EQ(file.info("50002_hips").dtype, "float32");
  const DynaSequence s = file.read("50002_hips");
  EXPECT_EQ(s.fps, kDynaFps);
  ASSERT_EQ(s.num_frames(), 2);
  EXPECT_EQ(s.frames[1](3, 2), 32.5);
  EXPECT_EQ(s.frames[0](2, 1), 21.0);
}

TEST(DynaFile, MalformedFilesGiveOneLineErrors) {
  const auto dir = sflsh::testing::scratch_dir();
  auto one_line = [](const std::string& message) { return message.find('\n') == std::string::npos; };

  const auto text = dir / "text.h5";
  std::ofstream(text) << "not hdf5\n";
  std::string e = error_of([&] { DynaFile f(text); });
  EXPECT_THAT(e, HasSubstr("not an HDF5 file"));
  EXPECT_TRUE(one_line(e)) << e;

  EXPECT_THAT(error_of([&] { DynaFile f(dir / "missing.h5"); }), HasSubstr("no such file"));

  const auto no_faces = dir / "no_faces.h5";
  write_raw(no_faces, RowMatrixX3i(), "50002_hips", {4, 3, 2}, std::vector<double>(24, 0.0));
  e = error_of([&] { DynaFile f(no_faces); });
  EXPECT_THAT(e, HasSubstr(no_faces.string() + ": faces: no such dataset"));
  EXPECT_TRUE(one_line(e)) << e;

  // HDF5 failures are said as what is wrong with the file, not as the library call that failed (issue 45).
  const auto group_faces = dir / "group_faces.h5";
  {
    H5::H5File file(group_faces.string(), H5F_ACC_TRUNC);
    file.createGroup("faces");
  }
  e = error_of([&] { DynaFile f(group_faces); });
  EXPECT_THAT(e,
              HasSubstr(group_faces.string() + ": faces: is a group, expected a dataset of F×3 integer face indices"));
  EXPECT_THAT(e, Not(HasSubstr("H5")));
  EXPECT_TRUE(one_line(e)) << e;

  const auto dangling = dir / "dangling.h5";
  write_raw(dangling, small_faces(), "50002_hips", {4, 3, 2}, std::vector<double>(24, 0.0));
  {
    H5::H5File file(dangling.string(), H5F_ACC_RDWR);
    H5Lcreate_soft("/nowhere", file.getId(), "50002_knees", H5P_DEFAULT, H5P_DEFAULT);
  }
  e = error_of([&] { DynaFile f(dangling); });
  EXPECT_THAT(e, HasSubstr(dangling.string() + ": 50002_knees: is a link that leads nowhere"));
  EXPECT_THAT(e, Not(HasSubstr("H5O")));
  EXPECT_TRUE(one_line(e)) << e;

  const auto rank2 = dir / "rank2.h5";
  write_raw(rank2, small_faces(), "50002_hips", {4, 3}, std::vector<double>(12, 0.0));
  e = error_of([&] { DynaFile f(rank2); });
  EXPECT_THAT(e, HasSubstr(rank2.string() + ": 50002_hips: shape (4, 3), expected (V, 3, T)"));
  EXPECT_TRUE(one_line(e)) << e;

  const auto transposed = dir / "transposed.h5";
  write_raw(transposed, small_faces(), "50002_hips", {2, 4, 3}, std::vector<double>(24, 0.0));
  EXPECT_THAT(error_of([&] { DynaFile f(transposed); }), HasSubstr("50002_hips: shape (2, 4, 3), expected (V, 3, T)"));

  const auto out_of_range = dir / "range.h5";
  RowMatrixX3i faces = small_faces();
  faces(1, 1) = 9;
  write_raw(out_of_range, faces, "50002_hips", {4, 3, 2}, std::vector<double>(24, 0.0));
  EXPECT_THAT(error_of([&] { DynaFile f(out_of_range); }),
              HasSubstr("faces: refers to vertex 9, but the sequences have 4 vertices"));

  const auto nan = dir / "nan.h5";
  std::vector<double> values(24, 0.0);
  values[(3 * 2 + 1) * 2 + 1] = std::numeric_limits<double>::quiet_NaN();  // vertex 2, y, frame 1
  write_raw(nan, small_faces(), "50002_hips", {4, 3, 2}, values);
  const DynaFile with_nan(nan);
  e = error_of([&] { with_nan.read("50002_hips"); });
  EXPECT_THAT(e, HasSubstr(nan.string() + ": 50002_hips: non-finite value in frame 1 (vertex 2)"));
  EXPECT_TRUE(one_line(e)) << e;

  e = error_of([&] { with_nan.read("50002_knees"); });
  EXPECT_THAT(e, HasSubstr(nan.string() + ": 50002_knees: no such sequence in the file, expected one of 50002_hips"));
  EXPECT_TRUE(one_line(e)) << e;

  const body::BodyModel model = sflsh::testing::synthetic_body();
  e = error_of([&] { with_nan.require_vertices(model); });
  EXPECT_THAT(e, HasSubstr(fmt::format("the registrations have 4 vertices, but the body model 'synthetic' has {}",
                                       model.num_vertices())));
  EXPECT_TRUE(one_line(e)) << e;
}

TEST(DynaFile, WriterRejectsBadSequencesAndLeavesNoFileBehind) {
  const auto dir = sflsh::testing::scratch_dir();
  const auto path = dir / "out.h5";
  {
    DynaWriter writer(path, small_faces());
    writer.add(ramp("50004_hips", 4, 2));
    DynaSequence bad = ramp("50004_knees", 4, 2);
    bad.frames[1](0, 0) = std::numeric_limits<double>::infinity();
    EXPECT_THAT(error_of([&] { writer.add(bad); }), HasSubstr("sequence '50004_knees' frame 1 has a non-finite value"));
    EXPECT_THAT(error_of([&] { writer.add(ramp("50004_punching", 5, 2)); }),
                HasSubstr("has 5 vertices, earlier sequences have 4"));
    EXPECT_THAT(error_of([&] { writer.add(ramp("faces", 4, 2)); }), HasSubstr("not a valid sequence key"));
  }  // destroyed without commit
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_EQ(sflsh::testing::count_entries(dir), 0u);  // the temporary is gone too
  EXPECT_THAT(error_of([&] { write_dyna_file(path, small_faces(), {ramp("50004_hips", 3, 2)}); }),
              HasSubstr("the faces refer to vertex 3, but sequence '50004_hips' has 3 vertices"));
  EXPECT_FALSE(std::filesystem::exists(path));
}

TEST(DynaFile, UnrelatedDatasetsAreReadPastWithANote) {
  // A dataset whose name cannot be '<subject>_<sequence>' (a note, a template kept beside the sequences) used to
  // make the whole file unusable; it is read past, and the file's notes say so.
  const auto dir = sflsh::testing::scratch_dir();
  const auto path = dir / "extra.h5";
  {
    DynaWriter writer(path, small_faces());
    writer.add(ramp("50004_shake_hips", 4, 3));
    writer.commit();
  }
  {
    H5::H5File file(path.string(), H5F_ACC_RDWR);
    const hsize_t n[1] = {5};
    const std::vector<double> values(5, 1.0);
    file.createDataSet("readme", H5::PredType::IEEE_F64LE, H5::DataSpace(1, n))
        .write(values.data(), H5::PredType::NATIVE_DOUBLE);
  }
  const DynaFile f(path);
  EXPECT_EQ(f.keys(), std::vector<std::string>{"50004_shake_hips"});
  ASSERT_EQ(f.notes().size(), 1u);
  EXPECT_THAT(f.notes()[0], HasSubstr("extra.h5: readme: not a <subject>_<sequence> key, read past"));
  EXPECT_EQ(f.read("50004_shake_hips").frames.size(), 3u);
}

TEST(DynaFile, KeysSplitIntoSubjectAndSequence) {
  EXPECT_EQ(subject_of("50004_one_leg_jump"), "50004");
  EXPECT_EQ(sequence_of("50004_one_leg_jump"), "one_leg_jump");
  EXPECT_EQ(subject_of("plain"), "plain");
  EXPECT_EQ(sequence_of("plain"), "");
  // Subject names with '_' (the open body's and Table 1's): split before the known sequence name.
  EXPECT_EQ(subject_of("OPEN_TRAIN_1_jiggle_on_toes"), "OPEN_TRAIN_1");
  EXPECT_EQ(sequence_of("OPEN_TRAIN_1_jiggle_on_toes"), "jiggle_on_toes");
  EXPECT_EQ(subject_of("DYNA_3_light_hopping_stiff"), "DYNA_3");
  EXPECT_EQ(subject_of("50004_shake_hips"), "50004");  // the longest name wins over "hips"
  EXPECT_EQ(sequence_of("50004_shake_hips"), "shake_hips");
  EXPECT_EQ(sequence_of("50004_hips"), "hips");
  EXPECT_EQ(subject_of("OPEN_TEST_2_dance"), "OPEN_TEST_2");
  // Unknown sequences: through the first all-digit part, else at the first '_'.
  EXPECT_EQ(subject_of("OPEN_TRAIN_1_cartwheel"), "OPEN_TRAIN_1");
  EXPECT_EQ(sequence_of("OPEN_TRAIN_1_cartwheel"), "cartwheel");
  EXPECT_EQ(subject_of("alice_cartwheel"), "alice");
  EXPECT_EQ(sequence_of("alice_cartwheel"), "cartwheel");
}

/// A chunked float32 dataset of shape (V, 3, T) of which only the first `written` frames are stored: the
/// file stays small whatever T is (the rest reads as the fill value 0).
void write_sparse(const std::filesystem::path& path, const std::string& name, hsize_t vertices, hsize_t frames,
                  const std::vector<RowMatrixX3d>& written) {
  H5::H5File file(path.string(), H5F_ACC_TRUNC);
  const RowMatrixX3i faces = small_faces();
  const hsize_t fd[2] = {static_cast<hsize_t>(faces.rows()), 3};
  file.createDataSet("faces", H5::PredType::STD_I64LE, H5::DataSpace(2, fd))
      .write(faces.data(), H5::PredType::NATIVE_INT);
  const hsize_t dims[3] = {vertices, 3, frames};
  const hsize_t chunk[3] = {std::min<hsize_t>(vertices, 1024), 3, 16};
  H5::DSetCreatPropList properties;
  properties.setChunk(3, chunk);
  const H5::DataSet dataset = file.createDataSet(name, H5::PredType::IEEE_F32LE, H5::DataSpace(3, dims), properties);
  const hsize_t count[3] = {vertices, 3, written.size()}, start[3] = {0, 0, 0};
  std::vector<double> values;
  for (hsize_t v = 0; v < vertices; ++v)
    for (int c = 0; c < 3; ++c)
      for (const RowMatrixX3d& frame : written) values.push_back(frame(static_cast<Eigen::Index>(v), c));
  H5::DataSpace selection = dataset.getSpace();
  selection.selectHyperslab(H5S_SELECT_SET, count, start);
  dataset.write(values.data(), H5::PredType::NATIVE_DOUBLE, H5::DataSpace(3, count), selection);
}

TEST(DynaFile, HugeSparseDatasetReadsOnlyTheFramesAsked) {
  // The fuzzed shape: (6929, 3, 1e7) float32 is 831 GB if read whole; it used to throw std::bad_alloc even
  // when 3 frames were asked for.
  const auto path = sflsh::testing::scratch_dir() / "sparse.h5";
  const int vertices = 6929;
  std::vector<RowMatrixX3d> written;
  for (int t = 0; t < 3; ++t) {
    RowMatrixX3d f(vertices, 3);
    for (int v = 0; v < vertices; ++v) f.row(v) << 0.25 * (v % 8), 0.5 * (v % 4) + 0.125 * t, 1.0 + 0.0625 * (v % 16);
    written.push_back(f);  // exactly representable in float32
  }
  write_sparse(path, "50004_jiggle_on_toes", vertices, 10000000, written);
  EXPECT_LT(std::filesystem::file_size(path), 10u << 20);

  const DynaFile file(path);
  EXPECT_EQ(file.info("50004_jiggle_on_toes").frames, 10000000);
  const DynaSequence three = file.read("50004_jiggle_on_toes", 3);
  ASSERT_EQ(three.num_frames(), 3);
  for (int t = 0; t < 3; ++t)
    EXPECT_EQ(three.frames[static_cast<std::size_t>(t)], written[static_cast<std::size_t>(t)]) << t;

  // All of it: refused by the read bound before anything is allocated.
  std::string e = error_of([&] { file.read("50004_jiggle_on_toes"); });
  EXPECT_THAT(e, HasSubstr(path.string() + ": 50004_jiggle_on_toes: 10000000 frames of 6929 vertices need"));
  EXPECT_THAT(e, HasSubstr("above the read limit of 2.15 GB (2 GiB); read fewer frames"));
  // Frame 3 was never written (all zeros): a collapsed registration, refused by name.
  e = error_of([&] { file.read("50004_jiggle_on_toes", 5); });
  EXPECT_THAT(e, HasSubstr(path.string() + ": 50004_jiggle_on_toes: frame 3 is degenerate: its vertices span 0 m"));
}

TEST(DynaFile, DegenerateOrAbsurdRegistrationsAreRefusedAtLoad) {
  const auto dir = sflsh::testing::scratch_dir();
  auto one_line = [](const std::string& message) { return message.find('\n') == std::string::npos; };

  const auto zeros = dir / "zeros.h5";
  write_raw(zeros, small_faces(), "50002_hips", {4, 3, 2}, std::vector<double>(24, 0.0));
  std::string e = error_of([&] { DynaFile(zeros).read("50002_hips"); });
  EXPECT_THAT(
      e,
      HasSubstr(zeros.string() +
                ": 50002_hips: frame 0 is degenerate: its vertices span 0 m, expected a body at least 0.01 m across"));
  EXPECT_TRUE(one_line(e)) << e;

  // Every vertex at one point (not at the origin) is as collapsed.
  const auto point = dir / "point.h5";
  std::vector<double> same(24);
  for (std::size_t i = 0; i < same.size(); ++i)
    same[i] = 0.3 + 0.1 * static_cast<double>((i / 2) % 3);  // [v][c][t]: c only
  write_raw(point, small_faces(), "50002_hips", {4, 3, 2}, same);
  EXPECT_THAT(error_of([&] { DynaFile(point).read("50002_hips"); }), HasSubstr("50002_hips: frame 0 is degenerate"));

  // Registrations scaled by 1e300: finite, but no body is 1e300 m away.
  const auto scaled = dir / "scaled.h5";
  DynaSequence far = ramp("50002_hips", 4, 2);
  for (RowMatrixX3d& f : far.frames) f *= 1e300;
  write_dyna_file(scaled, small_faces(), {far});
  e = error_of([&] { DynaFile(scaled).read("50002_hips"); });
  EXPECT_THAT(e, HasSubstr(scaled.string() +
                           ": 50002_hips: coordinate 3.2125e+301 m in frame 0 (vertex 3) is beyond ±10000 m"));
  EXPECT_TRUE(one_line(e)) << e;

  // A frame rate attribute that is not a capture rate.
  const auto slow = dir / "slow.h5";
  Attributes attributes;
  attributes.numbers["fps"] = {1e-9};
  write_dyna_file(slow, small_faces(), {ramp("50002_hips", 4, 2)}, attributes);
  EXPECT_THAT(error_of([&] { DynaFile(slow).read("50002_hips"); }),
              HasSubstr(slow.string() + ": 50002_hips: attribute fps = 1e-09 Hz is outside [1, 10000] Hz"));

  // A file with faces but no sequence: the missing sequence is named, not "0 vertices".
  const auto empty = dir / "empty.h5";
  write_raw(empty, small_faces(), "", {}, {});
  const DynaFile none(empty);
  EXPECT_THAT(error_of([&] { none.read("50004_hips"); }),
              HasSubstr(empty.string() +
                        ": 50004_hips: no such sequence in the file, which holds no sequence dataset (only 'faces')"));
  EXPECT_THAT(error_of([&] { none.require_vertices(sflsh::testing::synthetic_body()); }),
              HasSubstr(empty.string() + ": the file holds no sequence dataset (only 'faces')"));
}

}  // namespace
}  // namespace sflsh::validate
