// Test-bench top for the BioTac SPI RTL: timer clock, an HDL SPI master that cocotb drives one
// transaction at a time (so Python wakes per transaction, not per clock edge), and the wire from the
// bus to the host with MISO's 45 ns output delay.  Not synthesizable; not linted with the RTL.
`timescale 1ps/1ps
`default_nettype none

module tb_top #(
    parameter [4:0] SP = 5'b00000  // which sensors are BioTac SPs (see biotac_bus)
);
    // 1 MHz sensor timer: rising edges at 1, 2, 3 ... µs
    reg clk = 1'b1;
    always #500000 clk = ~clk;

    // controls set by cocotb
    reg  [4:0]  rst_n = 5'b00000;
    reg  [4:0]  present = 5'b11111;
    reg         pull_up = 1'b0;
    reg  [59:0] sample_code = 60'd0;
    reg  [4:0]  sample_ack = 5'd0;
    reg  [4:0]  flt_miso_flip_en = 5'd0, flt_mosi_flip_en = 5'd0, flt_miso_stuck_en = 5'd0;
    reg  [4:0]  flt_miso_stuck_val = 5'd0, flt_bad_parity = 5'd0, flt_slow = 5'd0;
    reg  [59:0] flt_miso_flip_bit = 60'd0, flt_mosi_flip_bit = 60'd0;
    reg  [319:0] provided = {320{1'b1}};  // every sensor provides every channel it recognises

    // transaction request (written by cocotb, then req_go toggled) and response
    reg  [2:0]  req_cs = 3'd0;
    reg  [11:0] req_nbits = 12'd0;
    reg  [63:0] req_mosi = 64'd0;
    reg  [31:0] req_half_ps = 32'd113636;
    reg         req_keep_cs = 1'b0;
    reg         req_go = 1'b0;
    reg  [63:0] rsp_miso = 64'd0;
    reg         rsp_done = 1'b0;

    // the wires
    reg         sck = 1'b0, mosi = 1'b0;
    reg  [2:0]  cs_code = 3'd0;
    wire        miso_at_bus;
    wire [4:0]  sample_req;
    wire [29:0] sample_channel;
    wire [59:0] user_registers;

    // The host samples MISO as it was 45 ns earlier (MISO becomes valid 45 ns after it changes): keep the
    // last changes of the bus line and look the value up at each rising edge.
    localparam integer VALID_DELAY_PS = 45000;
    time t_hist [0:7];
    reg  v_hist [0:7];
    integer h;
    initial for (h = 0; h < 8; h = h + 1) begin t_hist[h] = 0; v_hist[h] = 1'b0; end
    always @(miso_at_bus) begin
        for (h = 7; h > 0; h = h - 1) begin t_hist[h] = t_hist[h - 1]; v_hist[h] = v_hist[h - 1]; end
        t_hist[0] = $time;
        v_hist[0] = miso_at_bus;
    end
    function automatic miso_at_host();
        integer j;
        miso_at_host = v_hist[7];
        for (j = 7; j >= 0; j = j - 1)
            if ($time >= VALID_DELAY_PS && t_hist[j] <= $time - VALID_DELAY_PS) miso_at_host = v_hist[j];
    endfunction

    biotac_bus #(.SP(SP)) bus (
        .clk(clk), .rst_n(rst_n), .present(present), .pull_up(pull_up), .sck(sck), .mosi(mosi),
        .cs_code(cs_code), .miso(miso_at_bus), .sample_req(sample_req), .sample_channel(sample_channel),
        .sample_code(sample_code), .sample_ack(sample_ack),
        .flt_miso_flip_en(flt_miso_flip_en), .flt_miso_flip_bit(flt_miso_flip_bit),
        .flt_mosi_flip_en(flt_mosi_flip_en), .flt_mosi_flip_bit(flt_mosi_flip_bit),
        .flt_miso_stuck_en(flt_miso_stuck_en), .flt_miso_stuck_val(flt_miso_stuck_val),
        .flt_bad_parity(flt_bad_parity), .flt_slow(flt_slow), .user_registers(user_registers),
        .provided(provided));

    // SPI master: chip select falls (or changes) now, k-th rising SCK edge at (k + 1/2) periods,
    // chip select rises (unless kept) half a period after the last falling edge.
    integer k;
    always @(req_go) begin
        cs_code = req_cs;
        rsp_miso = 64'd0;
        for (k = 0; k < req_nbits; k = k + 1) begin
            mosi = (req_nbits - 1 - k < 64) ? req_mosi[req_nbits - 1 - k] : 1'b0;
            #(req_half_ps) sck = 1'b1;
            rsp_miso = {rsp_miso[62:0], miso_at_host()};
            #(req_half_ps) sck = 1'b0;
        end
        #(req_half_ps);
        if (!req_keep_cs) cs_code = 3'd0;
        mosi = 1'b0;
        rsp_done = ~rsp_done;
    end
endmodule

`default_nettype wire
