// Edge stepper: the Bresenham-style walk of one triangle edge, one sample row per clock.
// On load the edge's setup (crossing column q, remainder r, per-row step a + b/d) is
// taken; each following clock advances one row: q += a, r -= b, and when r < 0,
// r += d and q += 1 (carry). q and a are two's complement, r, b, d unsigned (0 <= r, b < d).
// Timing: valid/ready handshake (hs_pipe.v). An accepted input (a load or a step) updates
// the state register in its clock (the row recurrence is one clock, so one row per clock);
// the new state then leaves through LATENCY register stages (the preset's [cycles.raster]
// latency, 4: the raster stage's edge walk). One instance is one lane of the raster.
module edge_stepper #(
    parameter Q_BITS = 16,
    parameter D_BITS = 24,
    parameter LATENCY = 4
) (
    input  wire                     clk,
    input  wire                     rst,
    input  wire                     in_valid,
    output wire                     in_ready,
    output wire                     out_valid,
    input  wire                     out_ready,
    input  wire                     load,
    input  wire signed [Q_BITS-1:0] q_in,
    input  wire        [D_BITS-1:0] r_in,
    input  wire signed [Q_BITS-1:0] a,
    input  wire        [D_BITS-1:0] b,
    input  wire        [D_BITS-1:0] d,
    output wire signed [Q_BITS-1:0] q,
    output wire        [D_BITS-1:0] r,
    output wire                     carry
);
    reg signed [Q_BITS-1:0] sq, ra;
    reg        [D_BITS-1:0] sr, rb, rd;
    wire       [D_BITS:0]   rn  = {1'b0, sr} - {1'b0, rb};
    wire                    neg = rn[D_BITS];
    // The state after this clock's load or step.
    wire signed [Q_BITS-1:0] q_next = load ? q_in : neg ? sq + ra + 1'b1 : sq + ra;
    wire        [D_BITS-1:0] r_next = load ? r_in : neg ? rn[D_BITS-1:0] + rd : rn[D_BITS-1:0];
    wire                     c_next = !load && neg;
    wire take = in_valid && in_ready;
    always @(posedge clk) begin
        if (take) begin
            sq <= q_next;
            sr <= r_next;
            if (load) begin
                ra <= a;
                rb <= b;
                rd <= d;
            end
        end
    end
    hs_pipe #(.W(Q_BITS + D_BITS + 1), .DEPTH(LATENCY)) u_pipe (
        .clk(clk), .rst(rst), .in_valid(in_valid), .in_ready(in_ready),
        .in_data({q_next, r_next, c_next}), .out_valid(out_valid), .out_ready(out_ready),
        .out_data({q, r, carry}));
endmodule
