// Ordered dither: c = floor(x / 2^S + (m + 0.5) / 2^MB) saturated to OMAX, with the
// rank m read from an N x N mask ROM (N = 2^LOG_N, MB = 2*LOG_N rank bits) at
// ((py + oy) mod N, (px + ox) mod N); (ox, oy) is the frame's mask offset.
// Timing: valid/ready handshake (hs_pipe.v), the datapath followed by LATENCY register
// stages (the preset's [cycles.dither] latency, 1), one pixel per clock.
module dither_ordered #(
    parameter X_BITS   = 12,
    parameter S        = 4,
    parameter LOG_N    = 2,
    parameter O_BITS   = 8,
    parameter OMAX     = 255,
    parameter ROM_FILE = "dither_rom.hex",
    parameter LATENCY  = 1
) (
    input  wire              clk,
    input  wire              rst,
    input  wire              in_valid,
    output wire              in_ready,
    output wire              out_valid,
    input  wire              out_ready,
    input  wire [X_BITS-1:0] x,
    input  wire [LOG_N-1:0]  px,
    input  wire [LOG_N-1:0]  py,
    input  wire [LOG_N-1:0]  ox,
    input  wire [LOG_N-1:0]  oy,
    output wire [O_BITS-1:0] c,
    output wire              sat
);
    localparam MB = 2 * LOG_N;
    localparam T_BITS = X_BITS + MB + 2;
    reg [MB-1:0] rom [0:(1 << MB) - 1];
    initial $readmemh(ROM_FILE, rom);
    wire [LOG_N-1:0] xx = px + ox;
    wire [LOG_N-1:0] yy = py + oy;
    wire [MB-1:0] m = rom[{yy, xx}];
    wire [T_BITS-1:0] t = ({{(T_BITS-X_BITS){1'b0}}, x} << (MB + 1))
                        + ({{(T_BITS-MB-1){1'b0}}, m, 1'b1} << S);
    wire [T_BITS-1:0] q = t >> (S + MB + 1);
    wire over = q > OMAX;
    wire [O_BITS-1:0] c_next = over ? OMAX : q[O_BITS-1:0];
    hs_pipe #(.W(O_BITS + 1), .DEPTH(LATENCY)) u_pipe (
        .clk(clk), .rst(rst), .in_valid(in_valid), .in_ready(in_ready),
        .in_data({over, c_next}), .out_valid(out_valid), .out_ready(out_ready),
        .out_data({sat, c}));
endmodule
