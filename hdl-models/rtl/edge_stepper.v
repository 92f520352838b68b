// Edge stepper: the Bresenham-style walk of one triangle edge, one sample row per clock.
// On load the edge's setup (crossing column q, remainder r, per-row step a + b/d) is
// taken; each following clock advances one row: q += a, r -= b, and when r < 0,
// r += d and q += 1 (carry). q and a are two's complement, r, b, d unsigned (0 <= r, b < d).
// Timing: registered state; outputs are the state after the load or step of this clock.
module edge_stepper #(
    parameter Q_BITS = 16,
    parameter D_BITS = 24
) (
    input  wire                     clk,
    input  wire                     load,
    input  wire signed [Q_BITS-1:0] q_in,
    input  wire        [D_BITS-1:0] r_in,
    input  wire signed [Q_BITS-1:0] a,
    input  wire        [D_BITS-1:0] b,
    input  wire        [D_BITS-1:0] d,
    output reg  signed [Q_BITS-1:0] q,
    output reg         [D_BITS-1:0] r,
    output reg                      carry
);
    reg signed [Q_BITS-1:0] ra;
    reg        [D_BITS-1:0] rb, rd;
    wire       [D_BITS:0]   rn  = {1'b0, r} - {1'b0, rb};
    wire                    neg = rn[D_BITS];
    always @(posedge clk) begin
        if (load) begin
            q     <= q_in;
            r     <= r_in;
            ra    <= a;
            rb    <= b;
            rd    <= d;
            carry <= 1'b0;
        end else if (neg) begin
            r     <= rn[D_BITS-1:0] + rd;
            q     <= q + ra + 1'b1;
            carry <= 1'b1;
        end else begin
            r     <= rn[D_BITS-1:0];
            q     <= q + ra;
            carry <= 1'b0;
        end
    end
endmodule
