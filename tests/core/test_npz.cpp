#include "scratch_dir.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/npz.hpp>

#include <gmock/gmock.h>

#include <cstring>
#include <fstream>

using namespace sflsh;
using ::testing::HasSubstr;

TEST(Npz, RoundTripOfEveryKind) {
  const auto dir = sflsh::testing::scratch_dir();
  Eigen::MatrixXd m(2, 3);
  m << 1, 2, 3, 4, 5, 6;
  npz::write(dir / "a.npz", {{"matrix", npz::make_f64(m)},
                             {"ints", npz::make_i64({3}, {-1, 0, 7})},
                             {"u", npz::make_u32({2, 2}, {1, 2, 3, 4294967295u})},
                             {"name", npz::make_string("neutral")},
                             {"rate", npz::make_scalar(120.0)}});
  const npz::Reader reader(dir / "a.npz");
  EXPECT_THAT(reader.keys(), ::testing::UnorderedElementsAre("matrix", "ints", "u", "name", "rate"));
  const npz::Array back = reader.read("matrix");
  EXPECT_EQ(back.shape, (std::vector<std::size_t>{2, 3}));
  EXPECT_EQ(back.to_doubles(), (std::vector<double>{1, 2, 3, 4, 5, 6}));
  EXPECT_EQ(reader.read("ints").to_int64(), (std::vector<std::int64_t>{-1, 0, 7}));
  EXPECT_EQ(reader.read("u").to_int64().back(), 4294967295LL);
  EXPECT_EQ(reader.read("name").to_string(), "neutral");
  const npz::Array rate = reader.read("rate");
  EXPECT_TRUE(rate.shape.empty());
  EXPECT_EQ(rate.to_doubles().at(0), 120.0);
}

TEST(Npz, FortranOrderIsTransposedToCOrder) {
  // A 2×3 float64 array [[1,2,3],[4,5,6]] stored column-major, as numpy does for np.asfortranarray.
  std::string header = "{'descr': '<f8', 'fortran_order': True, 'shape': (2, 3), }";
  header.append(64 - (10 + header.size() + 1) % 64, ' ');
  header.push_back('\n');
  std::string raw = std::string("\x93NUMPY\x01\x00", 8) + static_cast<char>(header.size()) + '\0' + header;
  for (double v : {1.0, 4.0, 2.0, 5.0, 3.0, 6.0}) {
    char b[8];
    std::memcpy(b, &v, 8);
    raw.append(b, 8);
  }
  const std::vector<std::uint8_t> buffer(raw.begin(), raw.end());
  const npz::Array a = npz::parse_npy(buffer, "test");
  EXPECT_EQ(a.to_doubles(), (std::vector<double>{1, 2, 3, 4, 5, 6}));
}

TEST(Npz, FloatAndNarrowIntegerDtypes) {
  npz::Array a;
  a.kind = 'f';
  a.itemsize = 4;
  a.shape = {2};
  const float values[2] = {1.5f, -2.0f};
  a.bytes.resize(8);
  std::memcpy(a.bytes.data(), values, 8);
  const npz::Array back = npz::parse_npy(npz::serialize_npy(a), "f4");
  EXPECT_EQ(back.dtype(), "<f4");
  EXPECT_EQ(back.to_doubles(), (std::vector<double>{1.5, -2.0}));
}

TEST(Npz, MalformedInputsGiveNamedErrors) {
  const auto dir = sflsh::testing::scratch_dir();
  EXPECT_THAT([&] { npz::Reader r(dir / "missing.npz"); }, ::testing::ThrowsMessage<Error>(HasSubstr("missing.npz: file not found")));
  {
    std::ofstream(dir / "text.npz") << "this is not a zip archive";
  }
  EXPECT_THAT([&] { npz::Reader r(dir / "text.npz"); }, ::testing::ThrowsMessage<Error>(HasSubstr("not a readable .npz")));
  npz::write(dir / "ok.npz", {{"x", npz::make_scalar(1.0)}});
  const npz::Reader reader(dir / "ok.npz");
  EXPECT_THAT([&] { reader.read("y"); }, ::testing::ThrowsMessage<Error>(HasSubstr("missing key 'y'")));
  EXPECT_THAT([&] { npz::parse_npy({1, 2, 3}, "blob"); }, ::testing::ThrowsMessage<Error>(HasSubstr("blob: not a .npy")));
  std::vector<std::uint8_t> truncated = npz::serialize_npy(npz::make_f64({4}, {1, 2, 3, 4}));
  truncated.resize(truncated.size() - 8);
  EXPECT_THAT([&] { npz::parse_npy(truncated, "t"); }, ::testing::ThrowsMessage<Error>(HasSubstr("data truncated")));
  std::vector<std::uint8_t> object = npz::serialize_npy(npz::make_f64({1}, {1}));
  const std::string text(object.begin(), object.end());
  const auto pos = text.find("<f8");
  object[pos + 1] = 'O';
  EXPECT_THAT([&] { npz::parse_npy(object, "o"); }, ::testing::ThrowsMessage<Error>(HasSubstr("pickled")));
}
