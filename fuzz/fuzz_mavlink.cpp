// Fuzz target: the MAVLink parser and decoder (adaptseg::mavlink) on arbitrary bytes.
//
// The parser must never throw (bad input is counted, not thrown), never crash, never hold more
// than one frame between feeds, and account for every byte. Every frame it yields must decode
// without throwing, and its message, encoded again, must parse back into the same message. The
// bytes fed in one piece and in small chunks must give the same frames and the same counts.
// Anything else is a finding: the harness aborts and libFuzzer records the input.

#include <adaptseg/mavlink.hpp>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <span>
#include <vector>

namespace {

namespace mv = adaptseg::mavlink;

[[noreturn]] void finding(const char* what) {
  std::fprintf(stderr, "FINDING: %s\n", what);
  std::abort();
}

void require(bool ok, const char* what) {
  if (!ok) finding(what);
}

std::size_t wire_size(const mv::Frame& f) {
  return (f.version == mv::ProtocolVersion::v2 ? mv::kHeaderLengthV2 : mv::kHeaderLengthV1) + f.payload_length +
         mv::kChecksumLength + (f.signature ? mv::kSignatureLength : 0);
}

/// Feeds `data` in chunks of the given sizes (cycled; 0: all at once); returns the frames.
std::vector<mv::Frame> run(std::span<const std::uint8_t> data, std::span<const std::size_t> chunks,
                           mv::Parser& parser) {
  std::vector<mv::Frame> frames;
  std::size_t k = 0;
  for (std::size_t at = 0; at < data.size();) {
    const std::size_t c = chunks.empty() ? data.size() : chunks[k++ % chunks.size()];
    const std::size_t n = std::min(c, data.size() - at);
    parser.feed(data.subspan(at, n));
    at += n;
    while (auto f = parser.next()) frames.push_back(*f);
    require(parser.pending() <= mv::kMaxFrameLength, "the parser holds more than one frame between feeds");
  }
  return frames;
}

void check(std::span<const std::uint8_t> data) {
  mv::Parser whole;
  const std::vector<mv::Frame> frames = run(data, {}, whole);
  static constexpr std::size_t kChunks[] = {1, 3, 2, 7, 64, 5, 13, 300};
  mv::Parser chunked;
  const std::vector<mv::Frame> frames2 = run(data, kChunks, chunked);
  require(frames == frames2, "chunking changed the frames");
  require(whole.stats() == chunked.stats(), "chunking changed the counts");
  require(whole.pending() == chunked.pending(), "chunking changed the bytes held");

  std::uint64_t in_frames = 0;
  for (const mv::Frame& f : frames) in_frames += wire_size(f);
  const mv::ParseStats& s = whole.stats();
  require(s.bytes_fed == data.size(), "bytes_fed is not the input's size");
  require(s.frames_ok == frames.size(), "frames_ok is not the number of frames");
  require(s.bytes_fed == in_frames + s.skipped_bytes + s.dropped_bytes + whole.pending(), "a byte is unaccounted for");

  for (const mv::Frame& f : frames) {
    const mv::Message msg = mv::decode(f);
    const std::vector<std::uint8_t> again = mv::encode(msg, f.header());
    mv::Parser p;
    p.feed(again);
    const auto back = p.next();
    require(back.has_value() && !p.next().has_value(), "an encoded message does not parse back as one frame");
    require(back->header() == f.header() && back->message_id == f.message_id, "header or id changed in a round trip");
    require(mv::encode(mv::decode(*back), back->header()) == again, "a message changed in a round trip");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    check(std::span<const std::uint8_t>(data, size));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "FINDING: an exception escaped the codec: %s\n", e.what());
    std::abort();
  } catch (...) {
    finding("a non-std exception escaped the codec");
  }
  return 0;
}
