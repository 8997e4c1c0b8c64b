#include "link/record_source.hpp"

#include <cerrno>
#include <cstring>

namespace traj::link {

namespace {
constexpr int kFirstLinkVersion = 3;  // records carry their seq at offset 8
constexpr size_t kEndBytes = 16;
}  // namespace

RecordSource::RecordSource(const std::string& path) : name_(path == "-" ? "standard input" : path) {
  if (path == "-") {
    f_ = stdin;
  } else {
    f_ = std::fopen(path.c_str(), "rb");
    if (!f_) throw LinkError(path + ": " + std::strerror(errno));
    own_ = true;
  }
  Bytes head(8);
  if (!read_exact(head.data(), head.size())) fail("no stream header");
  const int version = get_u16(&head[4]);
  const size_t head_bytes = get_u16(&head[6]);
  if (std::memcmp(head.data(), "TRJS", 4) != 0) fail("not a segment stream (magic)");
  if (version < kFirstLinkVersion)
    fail("stream version " + std::to_string(version) + ": the link carries version " +
         std::to_string(kFirstLinkVersion) + " or later (records with sequence numbers); plan it again");
  if (head_bytes < 8 || head_bytes > 4096) fail("header size " + std::to_string(head_bytes));
  head.resize(head_bytes);
  if (!read_exact(head.data() + 8, head_bytes - 8)) fail("truncated header");
  // the stream reader checks the header: it alone knows every version's fields
  Bytes probe = head;
  const Bytes end = stream::encode_end(0, 0);
  probe.insert(probe.end(), end.begin(), end.end());
  const stream::ReadResult rd = stream::decode(probe, name_);
  if (!rd.complete) throw LinkError(rd.error);
  header_ = rd.header;
  record_bytes_ = stream::record_size(header_, stream::RecordKind::kFd);
}

RecordSource::~RecordSource() {
  if (own_) std::fclose(f_);
}

void RecordSource::fail(const std::string& what) const {
  throw LinkError(name_ + ": byte " + std::to_string(offset_) + ": " + what);
}

bool RecordSource::read_exact(uint8_t* p, size_t n) {
  const size_t k = std::fread(p, 1, n, f_);
  offset_ += k;
  return k == n;
}

bool RecordSource::next(Bytes& rec) {
  if (ended_) return false;
  const uint64_t at = offset_;
  const std::string seg = "segment " + std::to_string(count_);
  uint8_t type = 0;
  if (!read_exact(&type, 1)) fail("truncated: no end record after " + std::to_string(count_) + " segments");
  const size_t size = type == 0xFF ? kEndBytes : type == 1 ? record_bytes_ : 0;
  if (size == 0)
    fail(seg + ": record type " + std::to_string(type) + " (the board plays FD segments, type 1)");
  rec.resize(size);
  rec[0] = type;
  if (!read_exact(rec.data() + 1, size - 1)) fail(seg + ": truncated record");
  if (crc32(rec.data(), size - 4) != get_u32(&rec[size - 4]))
    throw LinkError(name_ + ": byte " + std::to_string(at) + ": " + seg + ": checksum mismatch");
  if (type == 0xFF) {
    if (get_u32(&rec[4]) != static_cast<uint32_t>(count_))
      throw LinkError(name_ + ": byte " + std::to_string(at) + ": end record counts " +
                      std::to_string(get_u32(&rec[4])) + " segments, the stream has " + std::to_string(count_));
    ended_ = true;
    return false;
  }
  if (get_u32(&rec[8]) != static_cast<uint32_t>(count_))
    throw LinkError(name_ + ": byte " + std::to_string(at + 8) + ": " + seg + ": sequence number " +
                    std::to_string(get_u32(&rec[8])));
  ++count_;
  return true;
}

}  // namespace traj::link
