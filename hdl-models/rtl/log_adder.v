// Gaussian-log adder: s = min(round((max(a,b) * 2^TF + sb(|a-b|)) / 2^TF), MAX); the
// zero code is the identity. sb comes from a table ROM of N = 2^ADDR_BITS (+1 when
// interpolating) entries of TD bits written by the Rust model; entry j holds sb(j 2^SHIFT).
// Without interpolation the address is round(d / 2^SHIFT); with it, linear
// interpolation between entries j and j+1 (rounded, ties up). Addresses >= N give 0.
// Timing: valid/ready handshake (hs_pipe.v), the datapath followed by LATENCY register
// stages (the preset's [cycles.logdomain] latency, 2), one add per clock.
module log_adder #(
    parameter FB        = 8,
    parameter TD        = 8,
    parameter TF        = 2,
    parameter ADDR_BITS = 6,
    parameter SHIFT     = 0,
    parameter INTERP    = 0,
    parameter MAX       = 255,
    parameter ROM_FILE  = "log_rom.hex",
    parameter LATENCY   = 2
) (
    input  wire          clk,
    input  wire          rst,
    input  wire          in_valid,
    output wire          in_ready,
    output wire          out_valid,
    input  wire          out_ready,
    input  wire [FB-1:0] a,
    input  wire [FB-1:0] b,
    output wire [FB-1:0] s
);
    localparam N = (1 << ADDR_BITS);
    localparam V_BITS = FB + TF + TD + 2;
    reg [TD-1:0] rom [0:N + INTERP - 1];
    initial $readmemh(ROM_FILE, rom);
    wire          ge = a >= b;
    wire [FB-1:0] m  = ge ? a : b;
    wire [FB-1:0] d  = ge ? a - b : b - a;
    reg  [FB:0]   j;
    reg  signed [V_BITS-1:0] sbv, lo, hi, fr;
    always @* begin
        if (INTERP != 0) begin
            j  = d >> SHIFT;
            fr = d & ((1 << SHIFT) - 1);
        end else begin
            j  = (SHIFT == 0) ? d : ((d + (1 << (SHIFT - 1))) >> SHIFT);
            fr = 0;
        end
        if (j >= N) begin
            sbv = 0;
            lo  = 0;
            hi  = 0;
        end else begin
            lo = rom[j];
            hi = (INTERP != 0) ? rom[j + 1] : 0;
            if (INTERP == 0 || SHIFT == 0)
                sbv = lo;
            else
                sbv = lo + (((hi - lo) * fr + (1 << (SHIFT - 1))) >>> SHIFT);
        end
    end
    wire [V_BITS-1:0] v = ({{(V_BITS-FB){1'b0}}, m} << TF) + sbv;
    wire [V_BITS-1:0] r = (TF == 0) ? v : ((v + (1 << (TF - 1))) >> TF);
    wire [FB-1:0] s_next = (a == 0) ? b : (b == 0) ? a : (r > MAX) ? MAX : r[FB-1:0];
    hs_pipe #(.W(FB), .DEPTH(LATENCY)) u_pipe (
        .clk(clk), .rst(rst), .in_valid(in_valid), .in_ready(in_ready), .in_data(s_next),
        .out_valid(out_valid), .out_ready(out_ready), .out_data(s));
endmodule
