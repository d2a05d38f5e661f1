#include "scratch_dir.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/npz.hpp>

#include <gmock/gmock.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>

namespace sflsh {

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
  EXPECT_THAT([&] { npz::Reader r(dir / "missing.npz"); },
              ::testing::ThrowsMessage<Error>(HasSubstr("missing.npz: file not found")));
  { std::ofstream(dir / "text.npz") << "this is not a zip archive"; }
  EXPECT_THAT([&] { npz::Reader r(dir / "text.npz"); },
              ::testing::ThrowsMessage<Error>(HasSubstr("not a readable .npz")));
  npz::write(dir / "ok.npz", {{"x", npz::make_scalar(1.0)}});
  const npz::Reader reader(dir / "ok.npz");
  EXPECT_THAT([&] { reader.read("y"); }, ::testing::ThrowsMessage<Error>(HasSubstr("missing key 'y'")));
  EXPECT_THAT(
      [&] {
        npz::parse_npy({1, 2, 3}, "blob");
      },
      ::testing::ThrowsMessage<Error>(HasSubstr("blob: not a .npy")));
  std::vector<std::uint8_t> truncated = npz::serialize_npy(npz::make_f64({4}, {1, 2, 3, 4}));
  truncated.resize(truncated.size() - 8);
  EXPECT_THAT([&] { npz::parse_npy(truncated, "t"); }, ::testing::ThrowsMessage<Error>(HasSubstr("data truncated")));
  std::vector<std::uint8_t> object = npz::serialize_npy(npz::make_f64({1}, {1}));
  const std::string text(object.begin(), object.end());
  const auto pos = text.find("<f8");
  object[pos + 1] = 'O';
  EXPECT_THAT([&] { npz::parse_npy(object, "o"); }, ::testing::ThrowsMessage<Error>(HasSubstr("pickled")));
}

namespace {

/// A .npy buffer with a hand-written header and raw data bytes.
std::vector<std::uint8_t> npy_with_header(const std::string& dict, const std::string& data = {}) {
  std::string header = dict;
  header.append(64 - (10 + header.size() + 1) % 64, ' ');
  header.push_back('\n');
  std::string raw = std::string("\x93NUMPY\x01\x00", 8) + static_cast<char>(header.size() & 0xFF) +
                    static_cast<char>(header.size() >> 8) + header + data;
  return {raw.begin(), raw.end()};
}

std::string parse_error(const std::vector<std::uint8_t>& buffer) {
  try {
    npz::parse_npy(buffer, "m.npz: x");
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST(Npz, OverflowingShapesAreRefusedBeforeAllocating) {
  // Elements × itemsize wrap around 2^64 to a small number: once this passed the truncation check.
  EXPECT_THAT(
      parse_error(npy_with_header("{'descr': '<f8', 'fortran_order': False, 'shape': (2305843009213693952,), }")),
      HasSubstr("m.npz: x: shape (2305843009213693952,) of dtype <f8 needs more than 2^64 bytes"));
  EXPECT_THAT(
      parse_error(npy_with_header("{'descr': '<f8', 'fortran_order': False, 'shape': (4294967296, 4294967296, 8), }")),
      HasSubstr("needs more than 2^64 bytes"));
  EXPECT_THAT(
      parse_error(npy_with_header("{'descr': '<f8', 'fortran_order': False, 'shape': (99999999999999999999,), }")),
      HasSubstr(
          "m.npz: x: shape (99999999999999999999,) has '99999999999999999999', expected non-negative whole numbers"));
  EXPECT_THAT(parse_error(npy_with_header("{'descr': '<f8', 'fortran_order': False, 'shape': (-1, 3), }")),
              HasSubstr("m.npz: x: shape (-1, 3) has '-1', expected non-negative whole numbers"));
  EXPECT_THAT(
      parse_error(npy_with_header("{'descr': '<f8', 'fortran_order': False, 'shape': (1000000, 3), }", "abc")),
      HasSubstr("m.npz: x: data truncated: shape (1000000, 3) of dtype <f8 needs 24000000 bytes, the member has 3"));
  // A zero extent empties the array whatever the others are.
  const npz::Array empty = npz::parse_npy(
      npy_with_header("{'descr': '<f8', 'fortran_order': False, 'shape': (0, 4294967296, 4294967296), }"), "e");
  EXPECT_EQ(empty.size(), 0u);

  // The same through an archive: the message names the file and the key.
  const auto dir = sflsh::testing::scratch_dir();
  npz::Array huge;
  huge.shape = {std::size_t{1} << 61, 8};  // header only: serialize_npy writes no data for it
  npz::write(dir / "huge.npz", {{"poses", huge}});
  const npz::Reader reader(dir / "huge.npz");
  EXPECT_THAT([&] { reader.read("poses"); },
              ::testing::ThrowsMessage<Error>(
                  HasSubstr((dir / "huge.npz").string() + ": poses: shape (2305843009213693952, 8)")));
}

TEST(Npz, UnsupportedDtypesAreRefusedByName) {
  for (const std::string descr : {"<c16", "<f16", "<M8", "|V8", "<b2", "<i3", "<U0", "<fx"})
    EXPECT_THAT(parse_error(npy_with_header("{'descr': '" + descr + "', 'fortran_order': False, 'shape': (1,), }",
                                            std::string(16, '\0'))),
                HasSubstr("m.npz: x: dtype '" + descr + "' is not supported, expected float16/32/64"))
        << descr;
  EXPECT_THAT(
      parse_error(npy_with_header("{'descr': '>f8', 'fortran_order': False, 'shape': (1,), }", std::string(8, '\0'))),
      HasSubstr("m.npz: x: big-endian dtype '>f8' is not supported, expected little-endian ('<f8')"));
  EXPECT_THAT(parse_error(npy_with_header("{'descr': [('a', '<f8')], 'fortran_order': False, 'shape': (1,), }")),
              HasSubstr("m.npz: x: .npy header has no plain 'descr'"));
  // Conversions name the array they were read from.
  const npz::Array text = npz::parse_npy(npz::serialize_npy(npz::make_string("female")), "m.npz: gender");
  EXPECT_THAT([&] { text.to_doubles(); },
              ::testing::ThrowsMessage<Error>(HasSubstr("m.npz: gender: dtype <U6 is not numeric")));
  const npz::Array fraction = npz::parse_npy(npz::serialize_npy(npz::make_f64({2}, {1.0, 2.5})), "m.npz: f");
  EXPECT_THAT(
      [&] { fraction.to_int64(); },
      ::testing::ThrowsMessage<Error>(HasSubstr("m.npz: f: element 1 is 2.5 (dtype <f8), expected an integer")));
}

TEST(Npz, Float16IsConvertedExactly) {
  // 1, -2, 65504 (largest), 2^-14 (smallest normal), 2^-24 (smallest subnormal), 1023·2^-24 (largest
  // subnormal), 0.333251953125, -0, +inf, -inf, NaN.
  const std::vector<std::uint16_t> halves = {0x3C00, 0xC000, 0x7BFF, 0x0400, 0x0001, 0x03FF,
                                             0x3555, 0x8000, 0x7C00, 0xFC00, 0x7E00};
  std::string data(2 * halves.size(), '\0');
  std::memcpy(data.data(), halves.data(), data.size());
  const npz::Array a = npz::parse_npy(
      npy_with_header("{'descr': '<f2', 'fortran_order': False, 'shape': (" + std::to_string(halves.size()) + ",), }",
                      data),
      "h");
  EXPECT_EQ(a.dtype(), "<f2");
  const std::vector<double> v = a.to_doubles();
  ASSERT_EQ(v.size(), halves.size());
  EXPECT_EQ(v[0], 1.0);
  EXPECT_EQ(v[1], -2.0);
  EXPECT_EQ(v[2], 65504.0);
  EXPECT_EQ(v[3], std::ldexp(1.0, -14));
  EXPECT_EQ(v[4], std::ldexp(1.0, -24));
  EXPECT_EQ(v[5], 1023.0 * std::ldexp(1.0, -24));
  EXPECT_EQ(v[6], 0.333251953125);
  EXPECT_EQ(v[7], 0.0);
  EXPECT_TRUE(std::signbit(v[7]));
  EXPECT_EQ(v[8], std::numeric_limits<double>::infinity());
  EXPECT_EQ(v[9], -std::numeric_limits<double>::infinity());
  EXPECT_TRUE(std::isnan(v[10]));
}

namespace {

/// Changes the CRC-32 of member `member` (0-based) in its local header (offset 14) and its central directory entry
/// (offset 16) consistently, as a bit flip in transit would leave the data and the checksum disagreeing.
void flip_crc(const std::filesystem::path& path, int member) {
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  in.close();
  const auto nth = [&](const char* signature) {
    std::size_t at = bytes.find(std::string(signature, 4));
    for (int k = 0; k < member && at != std::string::npos; ++k) at = bytes.find(std::string(signature, 4), at + 1);
    return at;
  };
  const std::size_t local = nth("PK\x03\x04"), central = nth("PK\x01\x02");
  ASSERT_NE(local, std::string::npos);
  ASSERT_NE(central, std::string::npos);
  bytes[local + 14] = static_cast<char>(bytes[local + 14] ^ 0x5A);
  bytes[central + 16] = static_cast<char>(bytes[central + 16] ^ 0x5A);
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

}  // namespace

TEST(Npz, MembersWithAWrongCrcAreRefused) {
  const auto dir = sflsh::testing::scratch_dir();
  const auto path = dir / "motion.npz";
  npz::write(path, {{"trans", npz::make_f64({2, 3}, {1, 2, 3, 4, 5, 6})}});
  EXPECT_EQ(npz::Reader(path).read("trans").to_doubles().back(), 6.0);

  flip_crc(path, 0);

  // Refused at open (every member's CRC is checked there), naming the member.
  EXPECT_THAT([&] { npz::Reader reader(path); },
              ::testing::ThrowsMessage<Error>(::testing::AllOf(HasSubstr(path.string() + ": trans.npy: "),
                                                               HasSubstr("CRC"), HasSubstr("corrupt archive"))));
}

TEST(Npz, AWrongCrcInAMemberNeverReadIsRefusedAtOpen) {
  // Issue 45: a damaged member that is never read went unnoticed; the archive is now refused as a whole.
  const auto dir = sflsh::testing::scratch_dir();
  const auto path = dir / "body.npz";
  npz::write(path, {{"a", npz::make_f64({2}, {1, 2})}, {"unused", npz::make_f64({3}, {3, 4, 5})}});
  EXPECT_EQ(npz::Reader(path).keys().size(), 2u);
  flip_crc(path, 1);  // the member never read
  EXPECT_THAT([&] { npz::Reader reader(path); },
              ::testing::ThrowsMessage<Error>(
                  ::testing::AllOf(HasSubstr(path.string() + ": unused.npy: "), HasSubstr("corrupt archive"))));
}

}  // namespace sflsh
