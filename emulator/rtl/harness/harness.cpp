// Stand-alone Verilator harness for the BioTac SPI RTL: plays a transfer schedule against biotac_bus
// with every SCK, chip-select and timer edge driven from C++ (no Python per edge). ADC requests are
// answered from a codes file written by the emulator. Timing and the host's MISO sampling follow
// emulator/spi/model.py exactly (k-th rising edge at (k + 1/2) periods; MISO read as it was 45 ns
// before the edge).
//
// usage: harness SCHEDULE CODES OUT
//   SCHEDULE: header (see struct Header) then Transfer records, little endian
//   CODES:    CodeRecord per conversion, in the order the sensors request them
//   OUT:      one uint64 MISO value per transfer, then uint64 counts of mismatched ADC requests, unused codes
//             and model evaluations
// usage: harness --stream
//   stdin:  a Header (n_transfers ignored), then batches: uint32 n_transfers, uint32 n_codes, uint32 n_faults,
//           Transfer records, CodeRecord records, SensorFaults records (fault changes: each sensor's fault ports
//           set to the record's when chip select falls for the batch's first transfer, before anything is
//           clocked, as the software bus applies a fault set between two of its calls; a batch with no transfers
//           keeps them for the next one); the RTL keeps its state and time runs on from batch to batch
//   stdout: "BTSPIOK\0" once the header is taken (a header refused: a message on stderr, exit 2, nothing on stdout);
//           then per batch, one uint64 MISO per transfer, then uint64 mismatched requests, unused codes, model
//           evaluations so far and requests waiting for their code; the harness exits when stdin ends.  A request
//           made when its sensor has no code queued waits for one (the RTL answers "E." meanwhile): the conversion
//           a batch ends on has its code in the next batch, first for that sensor, answered before anything is
//           played (the software bus judges its coupling by the bus's next activity, the next call)
#include <cstdint>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "Vbiotac_bus.h"
#include "verilated.h"

#pragma pack(push, 1)
// One sensor's fault ports (biotac_bus's flt_* bits of that sensor); flags are 0 or 1, bit positions 0..15.
struct SensorFaults {
    uint8_t sensor;  // 1..5
    uint8_t miso_flip_en, mosi_flip_en, stuck_en, stuck_val, bad_parity, slow, pad;
    uint16_t miso_flip_bit, mosi_flip_bit;
};
struct Header {
    char magic[8];  // "BTSPIV3\0"
    uint8_t present, pull_up;
    SensorFaults faults[5];  // sensors 1..5 in order
    uint64_t provided[5];  // per sensor, bit c set where it provides channel c (the others answer "EX")
    uint64_t n_transfers;
};
struct Transfer {
    int64_t t_ps;
    int32_t half_ps;
    uint16_t nbits;
    uint8_t cs, keep_cs;
    uint64_t mosi;
    uint8_t reset_mask;  // sensors reset just before this transfer (bit i = sensor i + 1)
    uint8_t present;     // with set_present = 1: the sensors plugged in from just before this transfer (hot-plugging;
    uint8_t set_present; // before the resets, so a sensor plugged back in is reset as it appears); 0: unchanged
    uint8_t pad[5];
};
struct CodeRecord {
    uint8_t sensor, channel;
    uint16_t code;
};
#pragma pack(pop)

static const int64_t HALF_TIMER_PS = 500000;  // 1 MHz timer: rising edges at whole microseconds
static const int64_t VALID_DELAY_PS = 45000;
static const int64_t RESET_PS = 100000;  // how long the harness holds reset before time 0
// An event up to 1 ns before a timer edge counts the edge as past, as the software model's ticks() does (it adds
// 1e-3 of a tick): it absorbs the float instants' rounding and the half periods rounded to whole picoseconds.
static const int64_t TICK_SLACK_PS = 1000;
// The RTL uses its timer only as differences (timer - a tick captured at a chip-select edge) compared with at
// most 100 ticks (the slow_response delay; the conversion time is 5). Once the bus has been idle this many ticks
// every such difference is past 100 whatever happens next, so the rest of an idle stretch changes nothing but
// the timer's count: it is skipped in whole ticks (the clock's phase kept) instead of clocked edge by edge.
// A virtual-time gap of hours then costs as much as one of 128 µs; the timer's count falls behind the true
// tick count by the ticks skipped, which no difference can see (the RTL's 32-bit timer would wrap after
// 71.6 min of idling; the reference model's timer does not, and neither do the differences here).
static const int64_t IDLE_TICKS_CLOCKED = 128;

struct Harness {
    std::unique_ptr<VerilatedContext> ctx{new VerilatedContext};
    std::unique_ptr<Vbiotac_bus> top{new Vbiotac_bus{ctx.get()}};
    int64_t now = 0, next_timer_edge = HALF_TIMER_PS;
    std::vector<std::deque<CodeRecord>> codes = std::vector<std::deque<CodeRecord>>(5);
    uint8_t last_req = 0;
    uint8_t waiting = 0;  // sensors whose latest request waits for its code (bit i = sensor i + 1)
    uint64_t mismatches = 0;
    std::deque<std::pair<int64_t, int>> line;  // recent (time, level) changes of MISO
    uint64_t evals = 0;
    std::vector<SensorFaults> pending_faults;  // set as chip select falls for the next transfer

    // Set sensor f.sensor's fault ports (not evaluated here).
    void set_faults(const SensorFaults& f) {
        int i = f.sensor - 1;
        uint8_t bit = (uint8_t)(1u << i);
        auto flag = [bit](uint8_t port, uint8_t on) { return (uint8_t)(on ? (port | bit) : (port & ~bit)); };
        auto field = [i](uint64_t port, uint16_t value) {
            return (port & ~(0xFFFULL << (12 * i))) | ((uint64_t)(value & 0xFFF) << (12 * i));
        };
        top->flt_miso_flip_en = flag(top->flt_miso_flip_en, f.miso_flip_en);
        top->flt_mosi_flip_en = flag(top->flt_mosi_flip_en, f.mosi_flip_en);
        top->flt_miso_stuck_en = flag(top->flt_miso_stuck_en, f.stuck_en);
        top->flt_miso_stuck_val = flag(top->flt_miso_stuck_val, f.stuck_val);
        top->flt_bad_parity = flag(top->flt_bad_parity, f.bad_parity);
        top->flt_slow = flag(top->flt_slow, f.slow);
        top->flt_miso_flip_bit = field(top->flt_miso_flip_bit, f.miso_flip_bit);
        top->flt_mosi_flip_bit = field(top->flt_mosi_flip_bit, f.mosi_flip_bit);
    }
    void apply_pending_faults() {
        if (pending_faults.empty()) return;
        for (const auto& f : pending_faults) set_faults(f);
        pending_faults.clear();
        eval();
    }

    void eval() {
        top->eval();
        ++evals;
        int level = top->miso;
        if (line.empty() || line.back().second != level) {
            line.emplace_back(now, level);
            if (line.size() > 64) line.pop_front();
        }
        serve();
    }
    void serve() {
        uint8_t req = top->sample_req;
        uint8_t changed = req ^ last_req;
        if (!changed) return;
        last_req = req;
        mismatches += (uint64_t)__builtin_popcount(changed & waiting);  // asked again before the code came
        waiting |= changed;
        answer();
    }
    // Answer each waiting request whose sensor has a code queued: the code if it is of the channel asked for, else
    // a mismatch (answered 0).  A request with no code queued keeps waiting (its sample_ack bit unchanged).
    void answer() {
        uint8_t ack = top->sample_ack;
        for (int i = 0; i < 5; ++i) {
            if (!(waiting >> i & 1) || codes[i].empty()) continue;
            int channel = (top->sample_channel >> (6 * i)) & 0x3F;
            uint16_t code = 0;
            if (codes[i].front().channel != channel) {
                ++mismatches;
            } else {
                code = codes[i].front().code;
                codes[i].pop_front();
            }
            top->sample_code = (top->sample_code & ~(0xFFFULL << (12 * i))) | ((uint64_t)code << (12 * i));
            ack = (uint8_t)((ack & ~(1u << i)) | (top->sample_req & (1u << i)));
            waiting &= (uint8_t)~(1u << i);
        }
        if (ack == top->sample_ack) return;
        top->sample_ack = ack;
        top->eval();
        ++evals;
    }
    uint64_t skipped_ticks = 0;  // timer ticks of idle stretches not clocked (see IDLE_TICKS_CLOCKED)

    // Run the timer up to time t (ps) with the bus's inputs unchanged (an idle stretch).
    void advance_to(int64_t t) {
        int64_t due = t + TICK_SLACK_PS;  // the timer edges that count as past at t
        if (next_timer_edge < due) {
            int64_t edges = (due - next_timer_edge + HALF_TIMER_PS - 1) / HALF_TIMER_PS;  // edges before due
            int64_t skipped = (edges - 2 * IDLE_TICKS_CLOCKED) / 2;  // whole ticks past the first clocked ones
            if (skipped > 0) {
                clock_edges(2 * IDLE_TICKS_CLOCKED);
                next_timer_edge += 2 * skipped * HALF_TIMER_PS;
                skipped_ticks += (uint64_t)skipped;
            }
        }
        while (next_timer_edge < due) clock_edges(1);
        now = std::max(now, t);  // (an edge clocked within the slack keeps time from running backwards)
    }
    void clock_edges(int64_t n) {
        for (int64_t k = 0; k < n; ++k) {
            now = next_timer_edge;
            top->clk = !top->clk;
            eval();
            next_timer_edge += HALF_TIMER_PS;
        }
    }
    int line_at(int64_t t) const {
        int level = line.empty() ? 0 : line.front().second;
        for (auto it = line.rbegin(); it != line.rend(); ++it)
            if (it->first <= t) return it->second;
        return level;
    }
};

static std::vector<char> read_file(const char* path) {
    FILE* f = std::fopen(path, "rb");
    if (!f) { std::fprintf(stderr, "harness: cannot open %s\n", path); std::exit(2); }
    std::vector<char> data;
    char buf[1 << 16];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) data.insert(data.end(), buf, buf + n);
    std::fclose(f);
    return data;
}

static void add_codes(Harness& H, const char* data, size_t n) {
    for (size_t k = 0; k + sizeof(CodeRecord) <= n; k += sizeof(CodeRecord)) {
        CodeRecord c;
        std::memcpy(&c, data + k, sizeof c);
        if (c.sensor >= 1 && c.sensor <= 5) H.codes[c.sensor - 1].push_back(c);
    }
}

// Whether a fault record names a sensor 1..5 with flags 0/1 and bit positions 0..15 (else a message, exit 2).
static bool valid_faults(const SensorFaults& f, const char* where) {
    bool ok = f.sensor >= 1 && f.sensor <= 5 && f.miso_flip_en <= 1 && f.mosi_flip_en <= 1 && f.stuck_en <= 1 &&
              f.stuck_val <= 1 && f.bad_parity <= 1 && f.slow <= 1 && f.miso_flip_bit < 16 && f.mosi_flip_bit < 16;
    if (!ok) std::fprintf(stderr, "harness: %s: a fault record for sensor %d outside its ranges (sensor 1..5, flags "
                          "0/1, bit positions 0..15)\n", where, f.sensor);
    return ok;
}

static bool valid_header(const Header& h) {
    for (int i = 0; i < 5; ++i)
        if (h.faults[i].sensor != i + 1 || !valid_faults(h.faults[i], "header")) return false;
    return true;
}

static void setup(Harness& H, const Header& h) {
    auto& top = *H.top;
    top.clk = 1;
    top.present = h.present;
    top.pull_up = h.pull_up;
    for (int i = 0; i < 5; ++i) H.set_faults(h.faults[i]);
    for (int i = 0; i < 5; ++i) {  // 64 bits per sensor, as two 32-bit words of the wide port
        top.provided[2 * i] = (uint32_t)h.provided[i];
        top.provided[2 * i + 1] = (uint32_t)(h.provided[i] >> 32);
    }
    // Reset is held for the 100 ns before time 0 and released at 0, so a transfer the host starts at 0 finds the
    // sensors ready with chip select falling when it says, as the software model does (released at 100 ns, a
    // transfer at 0 had its chip select fall late and its first bit read before the line held it).
    H.now = -RESET_PS;
    top.rst_n = 0;
    H.eval();
    H.advance_to(0);
    top.rst_n = 0x1F;
    H.eval();
}

static uint64_t play(Harness& H, const Transfer& t) {
    auto& top = *H.top;
    if (t.set_present) {
        H.advance_to(t.t_ps - 20);
        top.present = t.present;
        H.eval();
    }
    if (t.reset_mask) {
        H.advance_to(t.t_ps - 20);
        top.rst_n = 0x1F & ~t.reset_mask;
        H.eval();
        top.rst_n = 0x1F;
        H.eval();
    }
    H.advance_to(t.t_ps);
    H.apply_pending_faults();
    int64_t half = t.half_ps;
    top.cs_code = t.cs;
    top.mosi = t.nbits ? (t.nbits - 1 < 64 ? (t.mosi >> (t.nbits - 1)) & 1 : 0) : 0;
    H.eval();
    uint64_t miso = 0;
    for (int k = 0; k < t.nbits; ++k) {
        H.advance_to(t.t_ps + half * (2 * k + 1));
        top.sck = 1;
        H.eval();
        int bit = H.line_at(H.now - VALID_DELAY_PS);  // within spec this is the bit on the line now
        miso = (miso << 1) | (uint64_t)bit;
        H.advance_to(t.t_ps + half * 2 * (k + 1));
        top.sck = 0;
        int next = t.nbits - 2 - k;
        top.mosi = (next >= 0 && next < 64) ? (t.mosi >> next) & 1 : 0;
        H.eval();
    }
    H.advance_to(t.t_ps + half * (2 * t.nbits + 1));
    if (!t.keep_cs) {
        top.cs_code = 0;
        H.eval();
    }
    return miso;
}

static bool read_exact(void* buf, size_t n) { return std::fread(buf, 1, n, stdin) == n; }

// what the streaming harness answers a header it takes, before any batch
static const char STREAM_READY[8] = {'B', 'T', 'S', 'P', 'I', 'O', 'K', '\0'};

static int stream_mode() {
    Header h;
    if (!read_exact(&h, sizeof h) || std::string(h.magic, 7) != "BTSPIV3") {
        std::fprintf(stderr, "harness: malformed stream header\n");
        return 2;
    }
    if (!valid_header(h)) return 2;
    Harness H;
    setup(H, h);
    std::fwrite(STREAM_READY, 1, sizeof STREAM_READY, stdout);  // the header is taken: the host may go on
    std::fflush(stdout);
    uint32_t counts[3];
    std::vector<Transfer> trs;
    std::vector<char> codes;
    std::vector<SensorFaults> faults;
    std::vector<uint64_t> out;
    while (read_exact(counts, sizeof counts)) {
        trs.resize(counts[0]);
        codes.resize((size_t)counts[1] * sizeof(CodeRecord));
        faults.resize(counts[2]);
        if ((counts[0] && !read_exact(trs.data(), counts[0] * sizeof(Transfer))) ||
            (counts[1] && !read_exact(codes.data(), codes.size())) ||
            (counts[2] && !read_exact(faults.data(), counts[2] * sizeof(SensorFaults)))) {
            std::fprintf(stderr, "harness: truncated batch\n");
            return 2;
        }
        for (const auto& f : faults) {
            if (!valid_faults(f, "fault change")) return 2;
            H.pending_faults.push_back(f);
        }
        for (uint32_t i = 0; i < counts[0]; ++i) {
            if (trs[i].reset_mask > 0x1F || trs[i].set_present > 1 || (trs[i].set_present && trs[i].present > 0x1F)) {
                std::fprintf(stderr, "harness: transfer %u of a batch: a reset mask or sensors present outside the "
                             "five sensors (bits 0..4), or set_present other than 0/1\n", i);
                return 2;
            }
        }
        add_codes(H, codes.data(), codes.size());
        H.answer();  // the requests the last batch ended on, now that their codes came
        out.resize(counts[0] + 4);
        for (uint32_t i = 0; i < counts[0]; ++i) out[i] = play(H, trs[i]);
        uint64_t left = 0;
        for (auto& q : H.codes) left += q.size();
        out[counts[0]] = H.mismatches;
        out[counts[0] + 1] = left;
        out[counts[0] + 2] = H.evals;
        out[counts[0] + 3] = (uint64_t)__builtin_popcount(H.waiting);
        std::fwrite(out.data(), sizeof(uint64_t), out.size(), stdout);
        std::fflush(stdout);
    }
    return 0;
}

int main(int argc, char** argv) {
    if (argc == 2 && std::string(argv[1]) == "--stream") return stream_mode();
    if (argc != 4) { std::fprintf(stderr, "usage: harness SCHEDULE CODES OUT | harness --stream\n"); return 2; }
    std::vector<char> sched = read_file(argv[1]);
    std::vector<char> codes = read_file(argv[2]);
    if (sched.size() < sizeof(Header)) { std::fprintf(stderr, "harness: schedule too short\n"); return 2; }
    Header h;
    std::memcpy(&h, sched.data(), sizeof h);
    if (std::string(h.magic, 7) != "BTSPIV3" || sched.size() != sizeof h + h.n_transfers * sizeof(Transfer)) {
        std::fprintf(stderr, "harness: malformed schedule file\n");
        return 2;
    }
    if (!valid_header(h)) return 2;
    const Transfer* trs = reinterpret_cast<const Transfer*>(sched.data() + sizeof h);
    Harness H;
    add_codes(H, codes.data(), codes.size());
    setup(H, h);
    std::vector<uint64_t> out(h.n_transfers);
    for (uint64_t i = 0; i < h.n_transfers; ++i) out[i] = play(H, trs[i]);
    H.advance_to(H.now + 200000000);  // 200 µs for any last request
    H.mismatches += (uint64_t)__builtin_popcount(H.waiting);  // every code is in the file: one not there is a mismatch
    FILE* f = std::fopen(argv[3], "wb");
    if (!f) { std::fprintf(stderr, "harness: cannot write %s\n", argv[3]); return 2; }
    std::fwrite(out.data(), sizeof(uint64_t), out.size(), f);
    uint64_t left = 0;
    for (auto& q : H.codes) left += q.size();
    uint64_t tail[3] = {H.mismatches, left, H.evals};
    std::fwrite(tail, sizeof(uint64_t), 3, f);
    std::fclose(f);
    return 0;
}
