// Gamma LUT: frame code -> DAC code. The address is the integer part of the frame
// word (FRAC_BITS dropped by truncation); the ROM is written by the Rust model.
// Timing: one registered read (latency 1 clock, one lookup per clock).
module gamma_lut #(
    parameter ACC_BITS  = 12,
    parameter FRAC_BITS = 0,
    parameter DAC_BITS  = 8,
    parameter ROM_FILE  = "gamma_rom.hex"
) (
    input  wire                clk,
    input  wire [ACC_BITS-1:0] acc,
    output reg  [DAC_BITS-1:0] dac
);
    localparam ADDR_BITS = ACC_BITS - FRAC_BITS;
    reg [DAC_BITS-1:0] rom [0:(1 << ADDR_BITS) - 1];
    initial $readmemh(ROM_FILE, rom);
    always @(posedge clk) dac <= rom[acc[ACC_BITS-1:FRAC_BITS]];
endmodule
