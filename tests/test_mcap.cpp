// MCAP (docs/mcap.md): the container against the spec (https://mcap.dev/spec; the CRC32 recomputed
// here bit by bit, apart from zlib's), damaged files refused, and a CSP session through it: the
// joint log back bit for bit, /tf against the pose the emulator published, /errors, /scene.
// tests/mcap/read_with_mcap_core.mjs reads the same files with the reference reader (CTest).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "csp/dynamics/algorithms.hpp"
#include "csp/io/mcap.hpp"
#include "csp/run/mcap_export.hpp"
#include "csp/run/observers.hpp"
#include "csp/run/session_log.hpp"
#include "csp/run/sources.hpp"
#include "support.hpp"

namespace csp {
namespace {

// ----------------------------------------------------------------- an independent view of the bytes

// CRC-32 (ISO-HDLC, the zip/zlib polynomial 0xEDB88320 reflected), bit by bit from its definition.
uint32_t reference_crc32(std::string_view bytes) {
  uint32_t crc = 0xFFFFFFFFu;
  for (const char byte : bytes) {
    crc ^= static_cast<unsigned char>(byte);
    for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

uint64_t little_endian(std::string_view bytes, std::size_t at, int size) {
  uint64_t value = 0;
  for (int i = size - 1; i >= 0; --i) value = (value << 8) | static_cast<unsigned char>(bytes.at(at + i));
  return value;
}

struct RecordAt {
  uint8_t opcode;
  std::size_t offset, content, length;   // the record's start, its content's start and length
};

// The records from `begin` to `end`, by their opcode and length fields alone.
std::vector<RecordAt> records(std::string_view bytes, std::size_t begin, std::size_t end) {
  std::vector<RecordAt> found;
  for (std::size_t at = begin; at < end;) {
    const RecordAt record{static_cast<uint8_t>(bytes.at(at)), at, at + 9, little_endian(bytes, at + 1, 8)};
    EXPECT_LE(record.content + record.length, end) << "record at byte " << at;
    found.push_back(record);
    at = record.content + record.length;
  }
  return found;
}

std::string file_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << bytes;
}

std::string reading_error(const std::string& path) {
  try {
    mcap::read_file(path);
  } catch (const mcap::McapError& e) {
    return e.what();
  }
  return "no error";
}

// A small file: two channels, messages in two chunks' worth, a metadata record.
std::string write_small_file(int messages) {
  const std::string path = (test::temp_dir() / "small.mcap").string();
  mcap::Writer writer(path, "x-test", "csp test");
  const uint16_t schema = writer.add_schema("test.Value", "jsonschema", R"({"type":"object"})");
  const uint16_t a = writer.add_channel(schema, "/a", "json", {{"unit", "m"}});
  const uint16_t b = writer.add_channel(schema, "/b", "json");
  for (int i = 0; i < messages; ++i) {
    const std::string data = R"({"value":)" + std::to_string(i) + "}";
    writer.write_message(i % 3 == 0 ? b : a, 1000 * static_cast<uint64_t>(i), data);
  }
  writer.write_metadata({"test.meta", {{"key", "value"}}});
  writer.close();
  return path;
}

TEST(McapContainer, FollowsTheSpec) {
  const int kMessages = 30000;   // over 1 MiB of records: more than one chunk
  const std::string bytes = file_text(write_small_file(kMessages));
  const std::string_view magic("\x89MCAP0\r\n", 8);
  ASSERT_GT(bytes.size(), 2 * magic.size());
  EXPECT_EQ(bytes.substr(0, 8), magic);
  EXPECT_EQ(bytes.substr(bytes.size() - 8), magic);

  // The footer: the last 29 bytes before the magic.
  const std::size_t footer = bytes.size() - 8 - 29;
  ASSERT_EQ(bytes[footer], 0x02);
  EXPECT_EQ(little_endian(bytes, footer + 1, 8), 20u);
  const uint64_t summary_start = little_endian(bytes, footer + 9, 8);
  const uint64_t summary_offset_start = little_endian(bytes, footer + 17, 8);
  EXPECT_EQ(little_endian(bytes, footer + 25, 4),
            reference_crc32(std::string_view(bytes).substr(summary_start, footer + 25 - summary_start)));

  // The data section: Header, Schema, 2 Channels, then chunks each followed by its message indexes,
  // the Metadata, Data End (with the CRC of every byte before it).
  const std::vector<RecordAt> data = records(bytes, 8, summary_start);
  ASSERT_GE(data.size(), 7u);
  EXPECT_EQ(data[0].opcode, 0x01);
  EXPECT_EQ(data[1].opcode, 0x03);
  EXPECT_EQ(data[2].opcode, 0x04);
  EXPECT_EQ(data[3].opcode, 0x04);
  const RecordAt& data_end = data.back();
  ASSERT_EQ(data_end.opcode, 0x0F);
  EXPECT_EQ(data_end.length, 4u);
  EXPECT_EQ(little_endian(bytes, data_end.content, 4), reference_crc32(std::string_view(bytes).substr(0, data_end.offset)));
  EXPECT_EQ(data[data.size() - 2].opcode, 0x0C);

  int chunks = 0, messages = 0;
  std::map<std::size_t, std::size_t> chunk_at;   // chunk offset -> its record length
  for (const RecordAt& record : data) {
    if (record.opcode != 0x06) continue;
    ++chunks;
    chunk_at[record.offset] = record.length + 9;
    const std::size_t c = record.content;
    const uint64_t uncompressed_size = little_endian(bytes, c + 16, 8);
    const uint64_t crc = little_endian(bytes, c + 24, 4);
    EXPECT_EQ(little_endian(bytes, c + 28, 4), 0u) << "compression: the empty string";
    const uint64_t records_size = little_endian(bytes, c + 32, 8);
    EXPECT_EQ(records_size, uncompressed_size);
    EXPECT_EQ(c + 40 + records_size, record.content + record.length);
    const std::string_view inner = std::string_view(bytes).substr(c + 40, records_size);
    EXPECT_EQ(crc, reference_crc32(inner));
    for (const RecordAt& message : records(bytes, c + 40, c + 40 + records_size)) {
      EXPECT_EQ(message.opcode, 0x05);
      ++messages;
    }
  }
  EXPECT_GE(chunks, 2);
  EXPECT_EQ(messages, kMessages);

  // The summary: groups of one opcode each, as the Summary Offset records say; chunk indexes that
  // point at the chunks and their message indexes; statistics that count what the file holds.
  const std::vector<RecordAt> summary = records(bytes, summary_start, summary_offset_start);
  const std::vector<RecordAt> offsets = records(bytes, summary_offset_start, footer);
  ASSERT_EQ(offsets.size(), 5u);   // Schema, Channel, Statistics, Chunk Index, Metadata Index
  for (const RecordAt& offset : offsets) {
    ASSERT_EQ(offset.opcode, 0x0E);
    const auto opcode = static_cast<uint8_t>(bytes[offset.content]);
    const uint64_t start = little_endian(bytes, offset.content + 1, 8), length = little_endian(bytes, offset.content + 9, 8);
    for (const RecordAt& record : records(bytes, start, start + length)) EXPECT_EQ(record.opcode, opcode);
  }
  int chunk_indexes = 0;
  for (const RecordAt& record : summary) {
    const std::size_t c = record.content;
    if (record.opcode == 0x08) {
      ++chunk_indexes;
      const uint64_t chunk_offset = little_endian(bytes, c + 16, 8);
      ASSERT_TRUE(chunk_at.count(chunk_offset)) << "a chunk index at byte " << record.offset;
      EXPECT_EQ(little_endian(bytes, c + 24, 8), chunk_at[chunk_offset]);
      const uint64_t map_size = little_endian(bytes, c + 32, 4);
      for (std::size_t entry = c + 36; entry < c + 36 + map_size; entry += 10) {
        const uint64_t index_at = little_endian(bytes, entry + 2, 8);
        EXPECT_EQ(bytes[index_at], 0x07);
        EXPECT_EQ(little_endian(bytes, index_at + 9, 2), little_endian(bytes, entry, 2)) << "its channel";
      }
    } else if (record.opcode == 0x0B) {
      EXPECT_EQ(little_endian(bytes, c, 8), static_cast<uint64_t>(kMessages));
      EXPECT_EQ(little_endian(bytes, c + 8, 2), 1u);    // schemas
      EXPECT_EQ(little_endian(bytes, c + 10, 4), 2u);   // channels
      EXPECT_EQ(little_endian(bytes, c + 18, 4), 1u);   // metadata
      EXPECT_EQ(little_endian(bytes, c + 22, 4), static_cast<uint64_t>(chunks));
      EXPECT_EQ(little_endian(bytes, c + 26, 8), 0u);   // first log time
      EXPECT_EQ(little_endian(bytes, c + 34, 8), 1000u * (kMessages - 1));
    }
  }
  EXPECT_EQ(chunk_indexes, chunks);
  EXPECT_EQ(mcap::crc32("123456789"), 0xCBF43926u);   // the check value of CRC-32/ISO-HDLC
}

TEST(McapContainer, ReadsBackWhatItWrote) {
  const mcap::File file = mcap::read_file(write_small_file(100));
  EXPECT_EQ(file.profile, "x-test");
  EXPECT_EQ(file.library, "csp test");
  ASSERT_EQ(file.schemas.size(), 1u);
  EXPECT_EQ(file.schemas[0].name, "test.Value");
  ASSERT_EQ(file.channels.size(), 2u);
  EXPECT_EQ(file.channels[0].metadata.at("unit"), "m");
  ASSERT_EQ(file.messages.size(), 100u);
  for (std::size_t i = 0; i < file.messages.size(); ++i) {
    EXPECT_EQ(file.messages[i].log_time, 1000u * i);
    EXPECT_EQ(file.messages[i].data, R"({"value":)" + std::to_string(i) + "}");
    EXPECT_EQ(file.messages[i].channel_id, i % 3 == 0 ? 1 : 0);
  }
  ASSERT_EQ(file.metadata.size(), 1u);
  EXPECT_EQ(file.metadata[0].entries.at("key"), "value");
}

// Every prefix of a file is refused with its name and a byte offset, never read out of bounds.
TEST(McapContainer, RefusesATruncatedFileAtEveryLength) {
  const std::string bytes = file_text(write_small_file(200));
  const std::string path = (test::temp_dir() / "truncated.mcap").string();
  for (std::size_t size = 0; size < bytes.size(); size += 97) {
    write_bytes(path, bytes.substr(0, size));
    const std::string error = reading_error(path);
    EXPECT_EQ(error.rfind(path + ": byte ", 0), 0u) << "truncated to " << size << ": " << error;
  }
}

// A record length made larger (by one, or past the file) or smaller is refused, naming the record's byte.
TEST(McapContainer, RefusesAWrongLengthField) {
  const std::string path = write_small_file(50);
  const std::string bytes = file_text(path);
  const std::string damaged = (test::temp_dir() / "damaged.mcap").string();
  const uint64_t summary_start = little_endian(bytes, bytes.size() - 8 - 29 + 9, 8);
  for (const RecordAt& record : records(bytes, 8, summary_start)) {
    for (const uint64_t length : {record.length + 1, record.length - 1, uint64_t{0xFFFFFFFFFFFFFFF0u}}) {
      std::string copy = bytes;
      for (int i = 0; i < 8; ++i) copy[record.offset + 1 + i] = static_cast<char>((length >> (8 * i)) & 0xFF);
      write_bytes(damaged, copy);
      const std::string error = reading_error(damaged);
      EXPECT_EQ(error.rfind(damaged + ": byte ", 0), 0u) << "record at " << record.offset << ", length " << length << ": " << error;
    }
  }
}

TEST(McapContainer, RefusesACompressedChunkNamingItsCompression) {
  // The smallest file with a zstd chunk, encoded here by hand.
  std::string bytes(mcap::kMagic);
  const auto put = [&](uint64_t value, int size) {
    for (int i = 0; i < size; ++i) bytes.push_back(static_cast<char>((value >> (8 * i)) & 0xFF));
  };
  bytes.push_back(0x01);   // Header: two empty strings
  put(8, 8);
  put(0, 4);
  put(0, 4);
  const std::string compressed = "\x28\xb5\x2f\xfd-not-really";
  bytes.push_back(0x06);   // Chunk
  put(8 + 8 + 8 + 4 + 4 + 4 + 8 + compressed.size(), 8);
  put(0, 8);
  put(0, 8);
  put(100, 8);   // uncompressed size
  put(0, 4);     // no CRC
  put(4, 4);
  bytes += "zstd";
  put(compressed.size(), 8);
  bytes += compressed;
  bytes.push_back(0x0F);   // Data End, no CRC
  put(4, 8);
  put(0, 4);
  bytes.push_back(0x02);   // Footer: no summary
  put(20, 8);
  put(0, 8);
  put(0, 8);
  put(0, 4);
  bytes += mcap::kMagic;
  const std::string path = test::write_temp("zstd.mcap", bytes);
  const std::string error = reading_error(path);
  EXPECT_NE(error.find(path + ": byte 25: the chunk is compressed with `zstd`"), std::string::npos) << error;
}

TEST(McapContainer, RefusesWhatIsNoMcapFile) {
  const std::string csv = test::write_temp("not.mcap", "t,q1\n");
  EXPECT_NE(reading_error(csv).find("not an MCAP file"), std::string::npos) << reading_error(csv);
  EXPECT_NE(reading_error(test::temp_dir().string()).find("not a regular file"), std::string::npos);
  EXPECT_FALSE(mcap::is_mcap_file(csv));
  EXPECT_FALSE(mcap::is_mcap_file(test::temp_dir().string()));
}

// ----------------------------------------------------------------------------- a CSP session in it

const std::string kScene = std::string(CSP_SOURCE_DIR) + "/configs/scenes/ultrasound_abdomen.yaml";

const std::string kUltrasoundScenario = std::string(CSP_SOURCE_DIR) + "/configs/scenarios/medical/ultrasound_abdomen_scan.yaml";

// One short run of a scenario (by default a Panda with the Franka Hand) as `csp emulate --log` and
// `--lcm-log` write it.
struct RecordedSession {
  explicit RecordedSession(const std::string& scenario_path = test::kDefaultScenario) {
    scenario = rt::load_scenario(scenario_path);
    scenario.duration = 0.2;
    run::Run run(scenario);
    run::ControllerSource controller(run);
    run::LcmLogObserver lcm(lcm_log, run, controller.controller().mode);
    run::CsvLogObserver csv(csv_log, run.emulator());
    run.observe(lcm);
    run.observe(csv);
    EXPECT_TRUE(run.run(controller).observer_failure.empty());
  }
  ~RecordedSession() {
    std::filesystem::remove(csv_log);
    std::filesystem::remove(lcm_log);
  }
  std::string csv_log = (test::temp_dir() / "session.csv").string();
  std::string lcm_log = (test::temp_dir() / "session.lcmlog").string();
  rt::Scenario scenario;
};

// The session's mapping with the robot it recorded.
run::McapSession recorded_mapping(const RecordedSession& session, std::shared_ptr<const Scene> scene = nullptr) {
  return run::mcap_session(run::session_robot(session.lcm_log, "CSP_STATE", {}), std::move(scene));
}

std::vector<nlohmann::json> messages_on(const std::string& path, const std::string& topic) {
  const mcap::File file = mcap::read_file(path);
  const mcap::Channel* channel = file.channel(topic);
  std::vector<nlohmann::json> found;
  if (!channel) return found;
  for (const mcap::Message& message : file.messages)
    if (message.channel_id == channel->id) found.push_back(nlohmann::json::parse(message.data));
  return found;
}

template <typename Value>
bool same_bits(const std::vector<Value>& a, const std::vector<Value>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if constexpr (std::is_same_v<Value, std::string>) {
      if (a[i] != b[i]) return false;
    } else if (std::memcmp(&a[i], &b[i], sizeof(Value)) != 0) {
      return false;
    }
  }
  return true;
}

TEST(McapExport, GivesBackTheCsvJointLogBitForBit) {
  const RecordedSession session;
  JointLog log = read_joint_log_csv(session.csv_log);
  // A user's column and values whose shortest decimal forms are long.
  ExtensionColumn column{"x_marker", {}};
  for (std::size_t row = 0; row < log.size(); ++row) column.values.push_back(1.0 / 3.0 + 1e-17 * static_cast<double>(row));
  log.extensions.push_back(column);
  const std::string path = (test::temp_dir() / "roundtrip.mcap").string();
  const run::McapExportReport report = run::write_session_mcap(path, log, recorded_mapping(session));
  EXPECT_EQ(report.rows, log.size());

  const JointLog back = run::read_joint_log(path, "CSP_STATE");   // told from a CSV by its magic
  EXPECT_EQ(back.source, path);
  ASSERT_EQ(back.size(), log.size());
  for (const ColumnGroup& group : kJointLogSchema) {
    std::visit([&](auto member) { EXPECT_TRUE(same_bits(back.*member, log.*member)) << group.name; }, group.member);
  }
  ASSERT_EQ(back.extensions.size(), 1u);
  EXPECT_EQ(back.extensions[0].name, "x_marker");
  EXPECT_TRUE(same_bits(back.extensions[0].values, column.values));

  // The robot it recorded comes with it ("csp.session"), as from the LCM log.
  const run::SessionRobot robot = run::session_robot(path, "CSP_STATE", {});
  ASSERT_TRUE(robot.recorded);
  EXPECT_EQ(test::read_text(robot.robot_file), test::read_text(session.scenario.robot_file));
  EXPECT_EQ(robot.end_effector, "hand");
  EXPECT_EQ(robot.recorded_scenario, session.scenario.path);
}

// /tf composed from link0 to the EE, message by message, is the O_T_EE the emulator published.
void expect_transforms_compose_to_the_logged_pose(const std::string& path, const JointLog& log) {
  ASSERT_FALSE(log.O_T_EE.empty());
  const std::vector<nlohmann::json> tf = messages_on(path, "/tf");
  ASSERT_EQ(tf.size(), log.size());
  for (std::size_t row = 0; row < log.size(); ++row) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    std::string frame = "panda_link0";
    for (const nlohmann::json& transform : tf[row]["transforms"]) {
      ASSERT_EQ(transform["parent_frame_id"], frame);
      frame = transform["child_frame_id"];
      const auto& t = transform["translation"];
      const auto& r = transform["rotation"];
      Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
      step.linear() = Eigen::Quaterniond(r["w"], r["x"], r["y"], r["z"]).toRotationMatrix();
      step.translation() = Vector3(t["x"], t["y"], t["z"]);
      pose = pose * step;
    }
    ASSERT_EQ(frame, "panda_EE");
    const Eigen::Matrix4d logged = Eigen::Map<const Eigen::Matrix4d>(log.O_T_EE[row].data());   // column-major
    ASSERT_TRUE(test::near(pose.matrix(), logged, 1e-9)) << "row " << row;
  }
}

TEST(McapExport, TransformsComposeToTheLoggedEndEffectorPose) {
  const RecordedSession session;
  const JointLog log = read_joint_log_csv(session.csv_log);
  const std::string path = (test::temp_dir() / "tf.mcap").string();
  run::write_session_mcap(path, log, recorded_mapping(session));
  expect_transforms_compose_to_the_logged_pose(path, log);
}

// A scene that mounts a tool (the ultrasound probe): the EE frame is the tool's TCP, as the emulator's.
TEST(McapExport, TheEndEffectorOfASceneToolIsItsTcp) {
  const RecordedSession session(kUltrasoundScenario);
  const JointLog log = read_joint_log_csv(session.csv_log);
  const std::string path = (test::temp_dir() / "tool.mcap").string();
  run::write_session_mcap(path, log, recorded_mapping(session, session.scenario.emulator.scene));
  expect_transforms_compose_to_the_logged_pose(path, log);
}

TEST(McapExport, ErrorsAndModeChangesAreLogMessages) {
  const RecordedSession session;
  JointLog log = read_joint_log_csv(session.csv_log);
  ASSERT_FALSE(log.current_errors.empty());
  for (std::size_t row = 50; row < 60; ++row) {
    log.current_errors[row] = "[joint_position_limits_violation|cartesian_reflex]";
    log.robot_mode[row] = "Reflex";
  }
  const std::string path = (test::temp_dir() / "errors.mcap").string();
  run::write_session_mcap(path, log, recorded_mapping(session));
  std::vector<std::pair<int, std::string>> logged;
  for (const nlohmann::json& message : messages_on(path, "/errors")) logged.emplace_back(message["level"], message["message"]);
  // What the row's mode was before the reflex, and after.
  const std::string before = log.robot_mode[49], after = log.robot_mode[60];
  const std::vector<std::pair<int, std::string>> around = {
      {4, "current_errors [joint_position_limits_violation|cartesian_reflex]"},
      {3, "robot_mode Reflex"},
      {2, "current_errors []"},
      {2, "robot_mode " + after}};
  ASSERT_GE(logged.size(), around.size());
  EXPECT_TRUE(std::search(logged.begin(), logged.end(), around.begin(), around.end()) != logged.end())
      << "before " << before << ": " << nlohmann::json(logged).dump();
}

TEST(McapExport, WritesTheSceneOnceWithEveryObstacle) {
  const RecordedSession session;
  const JointLog log = read_joint_log_csv(session.csv_log);
  const auto scene_file = std::make_shared<const Scene>(load_scene(kScene));
  const Scene& scene = *scene_file;
  const std::string path = (test::temp_dir() / "scene.mcap").string();
  const run::McapExportReport report = run::write_session_mcap(path, log, recorded_mapping(session, scene_file));
  EXPECT_EQ(report.obstacles, scene.obstacles.size());
  const std::vector<nlohmann::json> updates = messages_on(path, "/scene");
  ASSERT_EQ(updates.size(), 1u);
  const nlohmann::json& entities = updates[0]["entities"];
  ASSERT_EQ(entities.size(), scene.obstacles.size());
  for (std::size_t i = 0; i < scene.obstacles.size(); ++i) {
    const nlohmann::json& entity = entities[i];
    EXPECT_EQ(entity["id"], scene.obstacles[i].name);
    EXPECT_EQ(entity["frame_id"], "panda_link0");
    const std::size_t primitives = entity["cubes"].size() + entity["spheres"].size() + entity["cylinders"].size();
    EXPECT_EQ(primitives, std::holds_alternative<Capsule>(scene.obstacles[i].shape) ? 3u : 1u) << entity.dump();
    if (const Box* box = std::get_if<Box>(&scene.obstacles[i].shape)) {
      const nlohmann::json& cube = entity["cubes"][0];
      EXPECT_DOUBLE_EQ(cube["size"]["x"].get<double>(), 2.0 * box->half_size.x());
      EXPECT_DOUBLE_EQ(cube["pose"]["position"]["z"].get<double>(), box->pose.translation.z());
    }
  }
}

// The message of reading an MCAP file as a joint log that must fail, or "no error".
std::string joint_log_reading_error(const std::string& path) {
  try {
    run::read_joint_log(path, "CSP_STATE");
  } catch (const JointLogError& e) {
    return e.what();
  }
  return "no error";
}

TEST(McapExport, RefusesAnMcapFileWithoutJointStates) {
  const std::string path = write_small_file(10);
  EXPECT_EQ(joint_log_reading_error(path), path + ": no /joint_states channel of JSON messages (csp.JointState, docs/mcap.md)");
}

// A /joint_states message that is no joint-log row names the message.
TEST(McapExport, RefusesAJointStateWithoutItsColumns) {
  const std::string path = (test::temp_dir() / "bad_state.mcap").string();
  {
    mcap::Writer writer(path, "", "test");
    const uint16_t channel = writer.add_channel(writer.add_schema("csp.JointState", "jsonschema", "{}"), "/joint_states", "json");
    writer.write_message(channel, 0, R"({"t":0,"position":[0,0,0,0,0,0,0],"velocity":[0,0,0,0,0,0,0]})");
  }
  EXPECT_EQ(joint_log_reading_error(path), path + ": /joint_states message 1 (log_time 0 ns): no `effort`");
}

// `csp log export --format mcap`: bad input is one line naming it, exit 2; the MCAP file it writes
// is read back by the same command (an MCAP file is a session log too).
TEST(McapExport, TheCommandRefusesBadInputInOneLine) {
  const RecordedSession session;
  const std::string mcap_file = (test::temp_dir() / "command.mcap").string();
  const test::ProgramRun exported = test::run_program(CSP_EXECUTABLE, {"log", "export", session.lcm_log, "--format", "mcap", "--out", mcap_file});
  ASSERT_EQ(exported.exit_code, 0) << exported.err;
  EXPECT_NE(exported.out.find("rows to " + mcap_file), std::string::npos) << exported.out;
  const std::string again = (test::temp_dir() / "again.mcap").string();
  EXPECT_EQ(test::run_program(CSP_EXECUTABLE, {"log", "export", mcap_file, "--format", "mcap", "--out", again}).exit_code, 0);
  EXPECT_TRUE(same_bits(run::read_joint_log(again, "CSP_STATE").q, read_joint_log_csv(session.csv_log).q));

  const std::string cut = test::write_temp("cut.mcap", file_text(mcap_file).substr(0, 5000));
  const std::string out = (test::temp_dir() / "out.mcap").string();
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"log", "export", cut, "--format", "mcap", "--out", out}, cut + ": byte "},
      {{"log", "export", session.csv_log, "--format", "mcap", "--robot", "missing.yaml", "--out", out}, "missing.yaml"},
      {{"log", "export", session.csv_log, "--format", "mcap", "--scene", "missing.yaml", "--out", out}, "missing.yaml"},
      {{"log", "export", session.lcm_log, "--scene", kScene, "--out", out}, "only with --format mcap"},
      {{"log", "export", session.lcm_log, "--format", "json", "--out", out}, "--format"},
  };
  for (const auto& [args, expected] : cases) {
    const test::ProgramRun run = test::run_program(CSP_EXECUTABLE, args);
    EXPECT_EQ(run.exit_code, 2) << args[2] << ": " << run.err;
    EXPECT_NE(run.err.find(expected), std::string::npos) << run.err;
    EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
  }
}

}  // namespace
}  // namespace csp
