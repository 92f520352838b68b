// Gamma LUT: frame code -> DAC code. The address is the integer part of the frame
// word (FRAC_BITS dropped by truncation); the ROM is written by the Rust model.
// Timing: valid/ready handshake (hs_pipe.v): the ROM read followed by LATENCY register
// stages (the preset's [cycles.gamma] latency, 2; synthesis may retime the first into the
// ROM's address register), one lookup per clock.
module gamma_lut #(
    parameter ACC_BITS  = 12,
    parameter FRAC_BITS = 0,
    parameter DAC_BITS  = 8,
    parameter ROM_FILE  = "gamma_rom.hex",
    parameter LATENCY   = 2
) (
    input  wire                clk,
    input  wire                rst,
    input  wire                in_valid,
    output wire                in_ready,
    input  wire [ACC_BITS-1:0] acc,
    output wire                out_valid,
    input  wire                out_ready,
    output wire [DAC_BITS-1:0] dac
);
    localparam ADDR_BITS = ACC_BITS - FRAC_BITS;
    reg [DAC_BITS-1:0] rom [0:(1 << ADDR_BITS) - 1];
    initial $readmemh(ROM_FILE, rom);
    hs_pipe #(.W(DAC_BITS), .DEPTH(LATENCY)) u_pipe (
        .clk(clk), .rst(rst), .in_valid(in_valid), .in_ready(in_ready),
        .in_data(rom[acc[ACC_BITS-1:FRAC_BITS]]), .out_valid(out_valid),
        .out_ready(out_ready), .out_data(dac));
endmodule
