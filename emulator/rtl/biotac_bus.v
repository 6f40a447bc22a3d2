// Five BioTac SPI peripherals sharing SCK, MOSI and MISO; the host's 3-bit select code picks one
// (1, 2, 4, 5, 6 -> sensors 1..5), all (7) or none (0). MISO is the OR of the selected sensors'
// outputs; with none selected it idles at pull_up, so an absent sensor reads 0x00 or 0xFF.  The SP parameter
// makes chosen sensors BioTac SPs (E20..E24 answer data instead of "EX"; their own property ROM).  ``provided``
// tells each sensor which channels it was built to provide (the others answer "EX").  A sensor not ``present``
// is held in reset and told it is absent: unplugged inside a chip-select window held open on it, the chip-select
// rise it sees acts on nothing (no result prepared, no conversion requested), and plugged back in it starts from
// power-on.
`default_nettype none

module biotac_bus #(
    parameter [4:0] SP = 5'b00000  // bit i set: sensor i + 1 is a BioTac SP (24 electrodes), else a BioTac (19)
) (
    input  wire        clk,
    input  wire [4:0]  rst_n,
    input  wire [4:0]  present,         // sensors plugged in
    input  wire        pull_up,         // MISO idle level
    input  wire        sck,
    input  wire        mosi,
    input  wire [2:0]  cs_code,
    output wire        miso,
    output wire [4:0]  sample_req,
    output wire [29:0] sample_channel,  // 6 bits per sensor
    input  wire [59:0] sample_code,     // 12 bits per sensor
    input  wire [4:0]  sample_ack,
    input  wire [4:0]  flt_miso_flip_en,
    input  wire [59:0] flt_miso_flip_bit,
    input  wire [4:0]  flt_mosi_flip_en,
    input  wire [59:0] flt_mosi_flip_bit,
    input  wire [4:0]  flt_miso_stuck_en,
    input  wire [4:0]  flt_miso_stuck_val,
    input  wire [4:0]  flt_bad_parity,
    input  wire [4:0]  flt_slow,
    output wire [59:0] user_registers,  // 12 bits per sensor
    input  wire [319:0] provided        // 64 bits per sensor: bit c set where it provides channel c
);
    localparam [14:0] ADDRESS = {3'b110, 3'b101, 3'b100, 3'b010, 3'b001};  // sensor 5 .. sensor 1
    wire [4:0] selected;
    wire [4:0] miso_each;
    genvar i;
    generate
        for (i = 0; i < 5; i = i + 1) begin : sensor
            assign selected[i] = present[i] && (cs_code == ADDRESS[3*i +: 3] || cs_code == 3'b111);
            biotac_spi #(.SENSOR(i + 1), .VARIANT(SP[i] ? 1 : 0)) spi (
                .clk(clk), .rst_n(rst_n[i] & present[i]), .present(present[i]), .sck(sck), .cs_n(!selected[i]),
                .mosi(mosi), .miso(miso_each[i]),
                .sample_req(sample_req[i]), .sample_channel(sample_channel[6*i +: 6]),
                .sample_code(sample_code[12*i +: 12]), .sample_ack(sample_ack[i]),
                .flt_miso_flip_en(flt_miso_flip_en[i]), .flt_miso_flip_bit(flt_miso_flip_bit[12*i +: 12]),
                .flt_mosi_flip_en(flt_mosi_flip_en[i]), .flt_mosi_flip_bit(flt_mosi_flip_bit[12*i +: 12]),
                .flt_miso_stuck_en(flt_miso_stuck_en[i]), .flt_miso_stuck_val(flt_miso_stuck_val[i]),
                .flt_bad_parity(flt_bad_parity[i]), .flt_slow(flt_slow[i]),
                .user_registers(user_registers[12*i +: 12]), .provided(provided[64*i +: 64]));
        end
    endgenerate
    assign miso = (|selected) ? (|(miso_each & selected)) : pull_up;
endmodule

`default_nettype wire
