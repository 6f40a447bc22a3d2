// The SPI peripheral of one BioTac, at register-transfer level.
//
// Behaviour is defined by emulator/spi/model.py (the reference); golden vectors and a randomized
// differential test check this RTL against it transaction by transaction. In short:
//   * chip-select fall: choose what MISO carries (prepared result, "E." if not ready, "E_" if none);
//   * SCK rising edge: capture MOSI; SCK falling edge: next MISO bit (SPI mode 0, MSB first);
//   * chip-select rise: act on the first 16 bits received (sample, read property, resend, write, errors).
// A recognised channel the emulated sensor was not built to provide (the ``provided`` port, the model's
// SensorPort.provided) answers "EX" and requests no conversion; it still restarts the 5-tick ADC-busy window,
// and a busy ADC answers "E-" first, as in the model.
// Delays are measured with a free-running 1 MHz timer (clk). The ADC code of a sampling command is
// requested through sample_req/sample_channel and answered by the test bench on sample_code/sample_ack,
// so the physics stays in the Python emulator. Faults enter through explicit ports.
`default_nettype none

module biotac_spi #(
    parameter integer SENSOR = 1,  // sensor number 1..5 (its serial number in the property ROM)
    parameter integer VARIANT = 0  // 0: BioTac, E1..E19 (channels 17..35); 1: BioTac SP, E1..E24 (17..40)
) (
    input  wire        clk,          // 1 MHz timer clock
    input  wire        rst_n,        // asynchronous reset (the "reset mid-stream" fault; held while unplugged)
    input  wire        present,      // plugged in: a sensor unplugged starts no conversion
    input  wire        sck,
    input  wire        cs_n,         // this sensor's chip select, decoded by the bus
    input  wire        mosi,
    output wire        miso,         // this sensor's MISO; 0 while deselected (the bus combines sensors)
    output reg         sample_req,   // toggles for every accepted sampling command
    output reg  [5:0]  sample_channel,
    input  wire [11:0] sample_code,  // the test bench's answer (the emulator's ADC code)
    input  wire        sample_ack,   // equals sample_req once sample_code answers the latest request
    input  wire        flt_miso_flip_en,
    input  wire [11:0] flt_miso_flip_bit,
    input  wire        flt_mosi_flip_en,
    input  wire [11:0] flt_mosi_flip_bit,
    input  wire        flt_miso_stuck_en,
    input  wire        flt_miso_stuck_val,
    input  wire        flt_bad_parity,
    input  wire        flt_slow,
    output wire [11:0] user_registers, // parameters 0..3 as written (3 bits each), for the test bench
    input  wire [63:0] provided        // bit c set: the emulated sensor was built to provide channel c
);
`include "biotac_props.vh"

    localparam [15:0] E_PARITY = 16'hA545, E_UNKNOWN = 16'hA53F, E_DELAY = 16'hA52E, E_BUSY = 16'hA52D,
                      E_CHANNEL = 16'hA558, E_NOTHING = 16'hA55F, E_READONLY = 16'hA552, E_WRITE = 16'hA557;
    localparam [1:0] K_WORD = 2'd0, K_PENDING = 2'd1, K_PROPERTY = 2'd2;

    localparam [2:0] SENSOR_ID = SENSOR[2:0];
    localparam [0:0] VARIANT_ID = VARIANT[0:0];
    localparam [5:0] LAST_ELECTRODE = (VARIANT == 1) ? 6'd40 : 6'd35;  // E24 or E19

    // ---------------------------------------------------------------- timer (1 µs ticks; delays are differences)
    reg [31:0] timer;
    always @(posedge clk or negedge rst_n) begin
        if (!rst_n) timer <= 32'd0;
        else timer <= timer + 32'd1;
    end

    // ---------------------------------------------------------------- helpers
    function automatic [15:0] data_word(input [11:0] value, input bad_parity);
        reg [7:0] b0, b1;
        begin
            b0 = {value[11:5], ~^value[11:5]};
            b1 = {value[4:0], 3'b000};
            b1[0] = ~^b1[7:1];
            data_word = {b0 ^ {7'b0, bad_parity}, b1};
        end
    endfunction

    function automatic is_sampled(input [5:0] ch);
        is_sampled = (ch <= 6'd3) || (ch >= 6'd17 && ch <= LAST_ELECTRODE);
    endfunction

    // ---------------------------------------------------------------- receive (SCK rising edges)
    reg [11:0] rx_count;
    reg [15:0] rx;
    wire mosi_seen = mosi ^ (flt_mosi_flip_en && rx_count == flt_mosi_flip_bit);
    always @(posedge sck or posedge cs_n) begin
        if (cs_n) begin
            rx_count <= 12'd0;
            rx <= 16'd0;
        end else begin
            if (rx_count < 12'd16) rx <= {rx[14:0], mosi_seen};
            if (rx_count != 12'hFFF) rx_count <= rx_count + 12'd1;
        end
    end

    // ---------------------------------------------------------------- prepared result (state)
    reg        prep_valid, prep_consumed;
    reg [1:0]  prep_kind;
    reg [15:0] prep_word;
    reg [7:0]  prep_prop;
    reg [31:0] prep_tick;
    reg        last_valid;
    reg [15:0] last_word;
    reg        sampling_valid;
    reg [31:0] sampling_tick;
    reg [2:0]  registers [0:3];
    assign user_registers = {registers[3], registers[2], registers[1], registers[0]};

    // ---------------------------------------------------------------- what MISO carries (chip-select fall)
    reg        serving;
    reg [1:0]  out_kind;   // K_WORD or K_PROPERTY
    reg [15:0] out_word;
    reg [7:0]  out_prop;
    wire [31:0] delay_ticks = flt_slow ? 32'd100 : 32'd50;
    always @(negedge cs_n or negedge rst_n) begin
        if (!rst_n) begin
            serving <= 1'b0;
            out_kind <= K_WORD;
            out_word <= E_NOTHING;
            out_prop <= 8'd0;
        end else if (!prep_valid || prep_consumed) begin
            serving <= 1'b0;
            out_kind <= K_WORD;
            out_word <= E_NOTHING;
        end else if (timer - prep_tick < delay_ticks || (prep_kind == K_PENDING && sample_ack != sample_req)) begin
            serving <= 1'b0;
            out_kind <= K_WORD;
            out_word <= E_DELAY;
        end else begin
            serving <= 1'b1;
            out_kind <= (prep_kind == K_PROPERTY) ? K_PROPERTY : K_WORD;
            out_word <= (prep_kind == K_PENDING) ? data_word(sample_code, flt_bad_parity) : prep_word;
            out_prop <= prep_prop;
        end
    end

    // ---------------------------------------------------------------- transmit (SCK falling edges)
    reg [11:0] tx_count;
    always @(negedge sck or posedge cs_n) begin
        if (cs_n) tx_count <= 12'd0;
        else if (tx_count != 12'hFFF) tx_count <= tx_count + 12'd1;
    end
    wire [8:0] byte_index = tx_count[11:3];
    reg  [7:0] out_byte;
    always @(*) begin
        if (out_kind == K_PROPERTY) out_byte = prop_byte(VARIANT_ID, SENSOR_ID, out_prop, byte_index);
        else if (byte_index == 9'd0) out_byte = out_word[15:8];
        else if (byte_index == 9'd1) out_byte = out_word[7:0];
        else out_byte = 8'h00;
    end
    wire bit_out = out_byte[3'd7 - tx_count[2:0]] ^ (flt_miso_flip_en && tx_count == flt_miso_flip_bit);
    assign miso = cs_n ? 1'b0 : (flt_miso_stuck_en ? flt_miso_stuck_val : bit_out);

    // ---------------------------------------------------------------- act on what was received (chip-select rise)
    wire [4:0]  n16 = (rx_count >= 12'd16) ? 5'd16 : rx_count[4:0];
    wire [7:0]  b0 = rx[n16 - 5'd1 -: 8];  // the first byte received (valid from 8 bits on)
    wire [7:0]  b1 = rx[7:0];
    wire [5:0]  channel = b0[6:1];
    wire [3:0]  param_n = b1[7:4];
    wire [2:0]  param_v = b1[3:1];
    wire        busy = sampling_valid && (timer - sampling_tick < 32'd5);

    task automatic prepare_word(input [15:0] w);
        begin
            prep_valid <= 1'b1;
            prep_consumed <= 1'b0;
            prep_kind <= K_WORD;
            prep_word <= w;
            prep_tick <= timer;
        end
    endtask

    // The ADC request toggles with every accepted sampling command (the main block's sampling branch below). It
    // has no reset: a reset is not a request (toggling it asked the bench for a conversion nobody commanded), and
    // the ADC is not reset, so a conversion already started completes; its result is never served (as in
    // emulator/spi/model.py).
    // A sensor unplugged inside a chip-select window holding a whole sampling command sees chip select rise as it
    // goes: it requests nothing (``present`` low), and prepares nothing (the bus holds it in reset).  A command
    // ending while a present sensor is held in reset still starts the ADC, which is not reset; nothing serves its
    // result, as the reset branch below prepares nothing.
    wire accept_sample = present && rx_count >= 12'd16 && provided[channel]
                         && b0[7] && (^b0) && is_sampled(channel) && !busy;
    initial sample_req = 1'b0;
    always @(posedge cs_n) begin
        if (accept_sample) sample_req <= ~sample_req;
    end

    integer r;
    always @(posedge cs_n or negedge rst_n) begin
        if (!rst_n) begin
            prep_valid <= 1'b0;
            prep_consumed <= 1'b0;
            prep_kind <= K_WORD;
            prep_word <= 16'd0;
            prep_prop <= 8'd0;
            prep_tick <= 32'd0;
            last_valid <= 1'b0;
            last_word <= 16'd0;
            sampling_valid <= 1'b0;
            sampling_tick <= 32'd0;
            sample_channel <= 6'd0;
            for (r = 0; r < 4; r = r + 1) registers[r] <= 3'd0;
        end else if (rx_count >= 12'd8) begin
            if (b0 == 8'h00) begin  // a read: consume what was served
                if (serving && (out_kind == K_PROPERTY || rx_count >= 12'd16)) begin
                    prep_consumed <= 1'b1;
                    if (out_kind == K_WORD) begin
                        last_valid <= 1'b1;
                        last_word <= out_word;
                    end
                end
            end else if (rx_count >= 12'd16) begin
                if (b0 == 8'h20 || b0 == 8'h50) begin
                    prepare_word(last_valid ? last_word : E_NOTHING);
                end else if (~^b0) begin
                    prepare_word(E_PARITY);
                end else if (b0[7]) begin
                    if (!is_sampled(channel)) begin
                        prepare_word(E_CHANNEL);
                    end else begin
                        sampling_valid <= 1'b1;
                        sampling_tick <= timer;
                        if (busy) begin
                            prepare_word(E_BUSY);
                        end else if (!provided[channel]) begin
                            prepare_word(E_CHANNEL);
                        end else begin
                            prep_valid <= 1'b1;
                            prep_consumed <= 1'b0;
                            prep_kind <= K_PENDING;
                            prep_tick <= timer;
                            sample_channel <= channel;  // sample_req toggles below
                        end
                    end
                end else if (b0 == 8'h61) begin
                    if (prop_known(b1)) begin
                        prep_valid <= 1'b1;
                        prep_consumed <= 1'b0;
                        prep_kind <= K_PROPERTY;
                        prep_prop <= b1;
                        prep_tick <= timer;
                    end else begin
                        prepare_word(E_CHANNEL);
                    end
                end else if (b0 == 8'h40) begin
                    if (~^b1) prepare_word(E_PARITY);
                    else if (param_n >= 4'd4) prepare_word(E_READONLY);
                    else if (param_v == 3'd7) prepare_word(E_WRITE);
                    else begin
                        registers[param_n[1:0]] <= param_v;
                        prepare_word(data_word({5'd0, param_n, param_v}, flt_bad_parity));
                    end
                end else begin
                    prepare_word(E_UNKNOWN);
                end
            end
        end
    end
endmodule

`default_nettype wire
